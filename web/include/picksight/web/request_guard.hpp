// Which HTTP requests picksight-web serves: the Host a request names and the
// Origin a browser sends must be among the machine's configured names (DNS
// rebinding, cross-site requests), and a request that changes anything must
// be one an HTML form or a cross-site page cannot make: a JSON content type
// and the X-PickSight header, which a browser sends cross-site only after a
// CORS preflight this server never grants (docs/SECURITY.md).
//
// Threading: HostNames is immutable after construction; share it freely.
#pragma once

#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace picksight::web {

// The header every state-changing request must carry (any non-empty value;
// the page sends "1").
constexpr const char* kRequestHeader = "X-PickSight";

class HostNames {
 public:
  // `names`: host names or addresses, any case; "*" allows every Host and
  // Origin (for a reverse proxy that checks them itself).
  explicit HostNames(const std::vector<std::string>& names);
  // What --allow-host defaults to: localhost, the loopback addresses, the
  // machine's host name (and NAME.local), every address of its interfaces
  // and the listen host unless it is a wildcard.
  static std::vector<std::string> defaults(const std::string& listen_host);

  // `host`: a Host header, "name", "name:port", "[v6]" or "[v6]:port".
  bool allowsHost(std::string_view host) const;
  // `origin`: an Origin header, "http(s)://host[:port]"; "null" never.
  bool allowsOrigin(std::string_view origin) const;
  // "a, b, c" or "any", for the start-up log.
  std::string describe() const;

 private:
  std::set<std::string> names_;  // lower case, without a trailing dot
  bool any_ = false;
};

// The parts of a request the guard looks at; absent headers are empty.
struct RequestFacts {
  std::string method;
  std::string host;
  std::string origin;
  bool has_origin = false;
  std::string content_type;
  std::string request_header;  // kRequestHeader's value
};

struct Refusal {
  int status = 403;
  std::string message;
};

// True for requests that may change something (everything but GET, HEAD
// and OPTIONS).
bool changesState(std::string_view method);

// Why the request is refused, or nothing when it may be served.
std::optional<Refusal> checkRequest(const HostNames& names, const RequestFacts& request);

}  // namespace picksight::web
