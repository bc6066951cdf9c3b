// The Host, Origin and cross-site checks of picksight-web's requests.
#include "picksight/web/request_guard.hpp"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <climits>

namespace picksight::web {
namespace {

std::string lower(std::string_view text) {
  std::string out(text);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

// "name", "name:port", "[v6]", "[v6]:port" -> the name in lower case without
// a trailing dot; nullopt when it is not one of these forms.
std::optional<std::string> hostOf(std::string_view authority) {
  std::string_view name;
  std::string_view rest;
  if (!authority.empty() && authority.front() == '[') {
    const size_t close = authority.find(']');
    if (close == std::string_view::npos) return std::nullopt;
    name = authority.substr(1, close - 1);
    rest = authority.substr(close + 1);
  } else {
    const size_t colon = authority.find(':');
    name = authority.substr(0, colon);
    rest = colon == std::string_view::npos ? std::string_view() : authority.substr(colon);
  }
  if (!rest.empty()) {
    if (rest.front() != ':' || rest.size() < 2 || rest.size() > 6) return std::nullopt;
    for (char c : rest.substr(1))
      if (!std::isdigit(static_cast<unsigned char>(c))) return std::nullopt;
  }
  if (!name.empty() && name.back() == '.') name.remove_suffix(1);
  if (name.empty()) return std::nullopt;
  for (char c : name)
    if (std::isspace(static_cast<unsigned char>(c)) || c == '/' || c == '@') return std::nullopt;
  return lower(name);
}

bool isWildcard(const std::string& host) {
  return host.empty() || host == "0.0.0.0" || host == "::" || host == "*";
}

}  // namespace

HostNames::HostNames(const std::vector<std::string>& names) {
  for (const auto& name : names) {
    if (name == "*") {
      any_ = true;
      continue;
    }
    // An IPv6 address as configured has no brackets ("fd00::7").
    const bool bare_v6 = name.find(':') != name.rfind(':') && name.front() != '[';
    if (auto host = hostOf(bare_v6 ? "[" + name + "]" : name)) names_.insert(*host);
  }
}

std::vector<std::string> HostNames::defaults(const std::string& listen_host) {
  std::vector<std::string> names = {"localhost", "127.0.0.1", "::1"};
  char host[HOST_NAME_MAX + 1] = {};
  if (::gethostname(host, sizeof(host) - 1) == 0 && host[0] != '\0') {
    const std::string name = host;
    names.push_back(name);
    names.push_back(name.substr(0, name.find('.')));             // the short name of an FQDN
    names.push_back(name.substr(0, name.find('.')) + ".local");  // mDNS
  }
  ifaddrs* list = nullptr;
  if (::getifaddrs(&list) == 0) {
    for (const ifaddrs* a = list; a != nullptr; a = a->ifa_next) {
      if (a->ifa_addr == nullptr) continue;
      char text[INET6_ADDRSTRLEN] = {};
      if (a->ifa_addr->sa_family == AF_INET) {
        const auto* v4 = reinterpret_cast<const sockaddr_in*>(a->ifa_addr);
        if (::inet_ntop(AF_INET, &v4->sin_addr, text, sizeof(text))) names.emplace_back(text);
      } else if (a->ifa_addr->sa_family == AF_INET6) {
        const auto* v6 = reinterpret_cast<const sockaddr_in6*>(a->ifa_addr);
        // A link-local address needs a zone in a URL, which browsers refuse.
        if (IN6_IS_ADDR_LINKLOCAL(&v6->sin6_addr)) continue;
        if (::inet_ntop(AF_INET6, &v6->sin6_addr, text, sizeof(text))) names.emplace_back(text);
      }
    }
    ::freeifaddrs(list);
  }
  if (!isWildcard(listen_host)) names.push_back(listen_host);
  std::sort(names.begin(), names.end());
  names.erase(std::unique(names.begin(), names.end()), names.end());
  return names;
}

bool HostNames::allowsHost(std::string_view host) const {
  if (any_) return true;
  auto name = hostOf(host);
  return name && names_.count(*name) > 0;
}

bool HostNames::allowsOrigin(std::string_view origin) const {
  if (any_) return true;
  std::string_view rest;
  if (origin.rfind("http://", 0) == 0)
    rest = origin.substr(7);
  else if (origin.rfind("https://", 0) == 0)
    rest = origin.substr(8);
  else
    return false;  // "null" (a sandboxed frame, a file: page) and other schemes
  return allowsHost(rest);
}

std::string HostNames::describe() const {
  if (any_) return "any";
  std::string out;
  for (const auto& name : names_) out += (out.empty() ? "" : ", ") + name;
  return out;
}

bool changesState(std::string_view method) {
  return method != "GET" && method != "HEAD" && method != "OPTIONS";
}

std::optional<Refusal> checkRequest(const HostNames& names, const RequestFacts& request) {
  // Every request, reads too: a page on a name that resolves to this
  // machine (DNS rebinding) sends that name as its Host.
  if (request.host.empty()) return Refusal{400, "a Host header is required"};
  if (!names.allowsHost(request.host))
    return Refusal{403, "forbidden: Host '" + request.host +
                            "' is not one of this server's names (--allow-host)"};
  if (request.has_origin && !names.allowsOrigin(request.origin))
    return Refusal{
        403, "forbidden: cross-site request from Origin '" + request.origin + "' (--allow-host)"};
  if (!changesState(request.method)) return std::nullopt;
  // A form can post text/plain, urlencoded or multipart bodies, never
  // JSON; and no cross-site page can add a header without a preflight.
  const std::string type = lower(request.content_type.substr(0, request.content_type.find(';')));
  const auto first = type.find_first_not_of(" \t");
  const auto last = type.find_last_not_of(" \t");
  if (first == std::string::npos || type.substr(first, last - first + 1) != "application/json")
    return Refusal{415,
                   "a request that changes something must have Content-Type: "
                   "application/json"};
  if (request.request_header.empty())
    return Refusal{403, std::string("a request that changes something must carry the ") +
                            kRequestHeader + " header"};
  return std::nullopt;
}

}  // namespace picksight::web
