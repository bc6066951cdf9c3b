// Command-line options and YAML configuration of picksight-web.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "picksight/common/allow_list.hpp"
#include "picksight/common/result.hpp"

namespace picksight::web {

// One video server: its frames (PUB) and control endpoints.
struct VideoServerEndpoints {
  std::string frames;
  std::string control;
};

// One vision app: its name, its results stream ("none": not subscribed) and
// the robot (or setup) port that commands from the page go to.
struct VisionAppEndpoint {
  std::string name;
  std::string results;
  std::string host;
  uint16_t port = 0;
};

struct WebOptions {
  std::string listen_host = "127.0.0.1";
  uint16_t listen_port = 8080;  // 0: any free port
  std::vector<VideoServerEndpoints> video_servers;
  std::vector<VisionAppEndpoint> vision_apps;
  std::string assets_dir;  // empty: the build tree's or the installed page
  AllowList allow;         // checked on every request
  // The names and addresses a request's Host and Origin may give (any case;
  // "*": any); empty: HostNames::defaults (request_guard.hpp).
  std::vector<std::string> allow_hosts;
  int jpeg_quality = 80;
  // Concurrent MJPEG and event streams; beyond it a 503, so that streams
  // never take every HTTP thread and starve the page.
  int max_streams = 48;
  // A connection must deliver its whole request within this (no byte
  // restarts it), and one address may hold per_address connections.
  std::chrono::milliseconds header_timeout{10000};
  int per_address = 32;
  // The users file (user_store.hpp); empty: users in memory only. With no
  // users, an admin with a random password printed once is made.
  std::string users_file;
  // A login ends after this long without a request (and after 12 h).
  std::chrono::seconds session_timeout{3600};
  // The audit trail (audit_trail.hpp); empty: audit.jsonl beside the users
  // file, or in memory without one.
  std::string audit_file;
  size_t audit_max_bytes = 1 << 20;
  int audit_files = 5;
  // GET /metrics without a login, for a scraper: with this bearer token
  // (read from --metrics-token FILE; empty: none), or from a peer of
  // metrics_allow (when metrics_allow_set). Neither: a login as for the rest.
  std::string metrics_token;
  AllowList metrics_allow;
  bool metrics_allow_set = false;
  // HTTPS with this certificate (PEM, its chain after it) and key (PEM, a
  // file others may not read); both or neither. redirect_port (with
  // redirect_host) serves plain HTTP that only redirects to HTTPS; 0: off.
  std::string tls_cert;
  std::string tls_key;
  std::string redirect_host;
  uint16_t redirect_port = 0;
  bool redirect = false;
  // --first-admin FILE: make the first admin of users_file, its password
  // to FILE, and exit (the package's postinst); empty: serve.
  std::string first_admin_file;
};

// Parses argv without the program name; errors name the option. With
// --config FILE the YAML map in FILE supplies options first (each key is an
// option without its dashes, a list repeats it) and the command line
// overrides them.
Result<WebOptions> parseWebArgs(const std::vector<std::string>& args, bool* help);
std::string webUsage();

// "HOST:PORT" ("[::1]:80" for IPv6); the error says what is wrong.
Result<std::pair<std::string, uint16_t>> parseHostPort(const std::string& text);

// The bearer token in `path` (whitespace around it dropped): 16..256
// printable characters, in a file others may not read; errors name the file.
Result<std::string> readMetricsToken(const std::string& path);

// The page's directory when --assets is not given: the source tree's
// web/assets when it exists (a build tree), else the installed one.
std::string defaultAssetsDir();

}  // namespace picksight::web
