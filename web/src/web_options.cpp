// picksight-web's options (picksight::cli) and its YAML file.
#include "picksight/web/web_options.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <set>

#include "picksight/cli/command_line.hpp"
#include "picksight/cli/config_file.hpp"
#include "picksight/common/atomic_file.hpp"
#include "picksight/common/text.hpp"
#include "picksight/web/web_errors.hpp"

namespace picksight::web {
namespace {

struct RawOptions {
  std::string listen = "127.0.0.1:8080";
  std::vector<std::string> video_servers;
  std::vector<std::string> vision_apps;
  std::string allow;
  std::vector<std::string> allow_hosts;
  int header_timeout_s = 10;
  int session_timeout_s = 3600;
  int audit_max_kib = 1024;
  std::string metrics_token_file;
  std::string metrics_allow;
  std::string http_redirect;
  std::string config_file;
};

std::string checkHostPort(const std::string& text) {
  auto parsed = parseHostPort(text);
  return parsed ? "" : parsed.error().message;
}

Result<VideoServerEndpoints> parseVideoServer(const std::string& text) {
  const auto fields = splitFields(text, ",");
  if (fields.size() != 2 || fields[0].empty() || fields[1].empty())
    return makeError(WebErrc::kBadConfig,
                     "'" + text + "': expected FRAMES_ENDPOINT,CONTROL_ENDPOINT");
  return VideoServerEndpoints{std::string(fields[0]), std::string(fields[1])};
}

Result<VisionAppEndpoint> parseVisionApp(const std::string& text) {
  const auto fields = splitFields(text, ",");
  if (fields.size() != 3 || fields[0].empty() || fields[1].empty())
    return makeError(WebErrc::kBadConfig,
                     "'" + text + "': expected NAME,RESULTS_ENDPOINT,HOST:PORT");
  auto host_port = parseHostPort(std::string(fields[2]));
  if (!host_port) return host_port.error();
  return VisionAppEndpoint{std::string(fields[0]), std::string(fields[1]), host_port->first,
                           host_port->second};
}

template <typename F>
cli::Validator checkEach(F parse) {
  return cli::checkValue([parse](const std::string& value) {
    auto parsed = parse(value);
    return parsed ? std::string() : parsed.error().message;
  });
}

cli::Validator checkAllowList() {
  return cli::checkValue([](const std::string& v) {
    auto list = AllowList::parse(v);
    return list ? std::string() : list.error().message;
  });
}

void defineOptions(cli::App& app, WebOptions& o, RawOptions& raw) {
  app.setHelpFlag("-h,--help", "print this help");
  app.addOption("--listen", raw.listen,
                "HOST:PORT to serve HTTP on (port 0: any free port; prints 'web http://...')")
      ->check(cli::checkValue(checkHostPort))
      ->showDefault();
  app.addOption("--video-server", raw.video_servers,
                "FRAMES_ENDPOINT,CONTROL_ENDPOINT of a video server (repeatable)")
      ->check(checkEach(parseVideoServer))
      ->takeAll();
  app.addOption("--vision-app", raw.vision_apps,
                "NAME,RESULTS_ENDPOINT,HOST:PORT of a vision app: its results stream "
                "('none': no results) and its robot or setup port (repeatable)")
      ->check(checkEach(parseVisionApp))
      ->takeAll();
  app.addOption("--assets", o.assets_dir, "directory of the page's files (index.html, ...)")
      ->showDefault();
  app.addOption("--allow", raw.allow,
                "peers allowed to connect: addresses or CIDR networks (default: everyone "
                "that reaches the listen address)")
      ->check(checkAllowList());
  app.addOption("--allow-host", raw.allow_hosts,
                "names and addresses this server answers to, as a request's Host and a "
                "browser's Origin give them (repeatable, or comma-separated; '*': any; default: "
                "localhost, loopback, this machine's names and addresses)")
      ->takeAll();
  app.addOption("--jpeg-quality", o.jpeg_quality, "JPEG quality of the streams")
      ->check(cli::range(10, 100))
      ->showDefault();
  app.addOption("--max-streams", o.max_streams, "concurrent MJPEG and event streams")
      ->check(cli::range(1, 200))
      ->showDefault();
  app.addOption("--header-timeout", raw.header_timeout_s,
                "seconds a connection has to deliver its whole request (header and body); "
                "no byte restarts it")
      ->check(cli::range(1, 300))
      ->showDefault();
  app.addOption("--per-address", o.per_address,
                "connections open at once from one address (streams included)")
      ->check(cli::range(1, 1024))
      ->showDefault();
  app.addOption("--users", o.users_file,
                "the users file (argon2id hashes, written through the page's Users tab); with no "
                "users, an 'admin' with a random password printed once (default: in memory)");
  app.addOption("--session-timeout", raw.session_timeout_s,
                "seconds without a request after which a login ends")
      ->check(cli::range(1, 86400))
      ->showDefault();
  app.addOption("--audit-file", o.audit_file,
                "the audit trail: every change made and every login through the page, one JSON "
                "record a line (default: audit.jsonl beside the --users file; without one, the "
                "newest 1000 records in memory)");
  app.addOption("--audit-max-kib", raw.audit_max_kib,
                "KiB one audit file may hold before the next is started (x --audit-files: "
                "65536 at most)")
      ->check(cli::range(16, 65536))
      ->showDefault();
  app.addOption("--audit-files", o.audit_files,
                "audit files kept, the current one included (the oldest beyond is deleted)")
      ->check(cli::range(2, 100))
      ->showDefault();
  app.addOption("--metrics-token", raw.metrics_token_file,
                "FILE holding a bearer token (16..256 printable characters; the file not "
                "readable by others) with which GET /metrics needs no login: "
                "'Authorization: Bearer TOKEN'");
  app.addOption("--metrics-allow", raw.metrics_allow,
                "peers (addresses or CIDR networks) that may GET /metrics without a login")
      ->check(checkAllowList());
  app.addOption("--tls-cert", o.tls_cert,
                "PEM certificate (its chain after it): serve HTTPS instead of HTTP; with "
                "--tls-key")
      ->check(cli::existingFile());
  app.addOption("--tls-key", o.tls_key,
                "PEM private key of --tls-cert (a file others may not read)")
      ->check(cli::existingFile());
  app.addOption("--http-redirect", raw.http_redirect,
                "HOST:PORT of a plain-HTTP port that only redirects to the HTTPS one (with "
                "--tls-cert; port 0: any free port, printed as 'redirect http://...')")
      ->check(cli::checkValue(checkHostPort));
  app.addOption("--first-admin", o.first_admin_file,
                "with --users: when the users file holds no user, make 'admin' with a random "
                "password, write the password to FILE (created 0600, never overwritten) and "
                "exit; with users already, exit and change nothing (for installers)");
  app.addOption("--config", raw.config_file,
                "YAML file of options, each named as its flag without dashes "
                "(lists for the repeatable ones); the command line overrides it");
}

cli::App webApp() {
  return cli::App(
      "Web HMI of a PickSight cell: live cameras, vision results, camera settings, "
      "teaching and calibration from a browser.",
      "picksight-web");
}

Result<WebOptions> finishOptions(WebOptions o, RawOptions& raw) {
  // The validators accepted these: the conversions cannot fail.
  auto listen = parseHostPort(raw.listen);
  o.listen_host = listen->first;
  o.listen_port = listen->second;
  for (const auto& v : raw.video_servers) o.video_servers.push_back(*parseVideoServer(v));
  std::set<std::string> names;
  for (const auto& v : raw.vision_apps) {
    o.vision_apps.push_back(*parseVisionApp(v));
    if (!names.insert(o.vision_apps.back().name).second)
      return makeError(WebErrc::kBadConfig,
                       "--vision-app: name '" + o.vision_apps.back().name + "' given twice");
  }
  if (!raw.allow.empty()) o.allow = *AllowList::parse(raw.allow);
  o.header_timeout = std::chrono::seconds(raw.header_timeout_s);
  o.session_timeout = std::chrono::seconds(raw.session_timeout_s);
  o.audit_max_bytes = static_cast<size_t>(raw.audit_max_kib) * 1024;
  if (!raw.metrics_token_file.empty()) {
    auto token = readMetricsToken(raw.metrics_token_file);
    if (!token) return makeError(WebErrc::kBadConfig, "--metrics-token: " + token.error().message);
    o.metrics_token = *token;
  }
  if (!raw.http_redirect.empty()) {
    auto redirect = parseHostPort(raw.http_redirect);
    o.redirect_host = redirect->first;
    o.redirect_port = redirect->second;
    o.redirect = true;
  }
  if (!raw.metrics_allow.empty()) {
    o.metrics_allow = *AllowList::parse(raw.metrics_allow);
    o.metrics_allow_set = true;
  }
  if (o.audit_file.empty() && !o.users_file.empty())
    o.audit_file = (std::filesystem::path(o.users_file).parent_path() / "audit.jsonl").string();
  for (const auto& v : raw.allow_hosts)
    for (const auto& name : splitFields(v, ","))
      if (!name.empty()) o.allow_hosts.emplace_back(name);
  return o;
}

}  // namespace

Result<std::string> readMetricsToken(const std::string& path) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0)
    return makeError(WebErrc::kBadConfig, path + ": " + std::strerror(errno));
  // A secret, as ssh treats a private key: others may not read it (the
  // service's group may).
  if ((info.st_mode & 0007) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof(mode), "%04o", static_cast<unsigned>(info.st_mode & 07777));
    return makeError(WebErrc::kBadConfig, std::string("permissions ") + mode + " for " + path +
                                              " are too open: others may read it (chmod 640)");
  }
  if (info.st_size > 4096)
    return makeError(WebErrc::kBadConfig, path + ": over 4096 bytes, not a token");
  auto text = readFile(path);
  if (!text) return text.error();
  const size_t first = text->find_first_not_of(" \t\r\n");
  const size_t last = text->find_last_not_of(" \t\r\n");
  const std::string token =
      first == std::string::npos ? std::string() : text->substr(first, last - first + 1);
  if (token.size() < 16 || token.size() > 256)
    return makeError(WebErrc::kBadConfig, path + ": the token must be 16..256 characters");
  for (char c : token)
    if (c <= ' ' || c > '~')
      return makeError(WebErrc::kBadConfig,
                       path + ": the token must be printable ASCII without spaces");
  return token;
}

Result<std::pair<std::string, uint16_t>> parseHostPort(const std::string& text) {
  const size_t colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0)
    return makeError(WebErrc::kBadConfig, "'" + text + "': expected HOST:PORT");
  std::string host = text.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']')
    host = host.substr(1, host.size() - 2);
  const auto port = parseInt(std::string_view(text).substr(colon + 1));
  if (!port || *port < 0 || *port > 65535)
    return makeError(WebErrc::kBadConfig, "'" + text + "': the port must be 0..65535");
  return std::make_pair(host, static_cast<uint16_t>(*port));
}

std::string defaultAssetsDir() {
  std::error_code ec;
  if (std::filesystem::is_regular_file(PICKSIGHT_WEB_SOURCE_ASSETS "/index.html", ec))
    return PICKSIGHT_WEB_SOURCE_ASSETS;
  return PICKSIGHT_WEB_INSTALLED_ASSETS;
}

std::string webUsage() { return cli::toolUsage(webApp, defineOptions); }

namespace {

// What options say together, once the file's and the line's are merged
// (finishOptions sees the line alone first).
Result<void> checkCombinations(const WebOptions& o) {
  if (!o.first_admin_file.empty() && o.users_file.empty())
    return makeError(WebErrc::kBadConfig, "--first-admin needs --users FILE");
  if (o.tls_cert.empty() != o.tls_key.empty())
    return makeError(WebErrc::kBadConfig, "--tls-cert and --tls-key go together");
  if (!o.tls_key.empty()) {
    struct stat info {};
    if (::stat(o.tls_key.c_str(), &info) == 0 && (info.st_mode & 0007) != 0)
      return makeError(WebErrc::kBadConfig,
                       "--tls-key: " + o.tls_key + " may be read by others (chmod 640 or 600)");
  }
  // The trail is read back and exported whole: 64 MiB in all at most.
  if (o.audit_max_bytes * static_cast<size_t>(o.audit_files) > (size_t{64} << 20))
    return makeError(WebErrc::kBadConfig,
                     "--audit-max-kib x --audit-files: at most 65536 KiB in all");
  if (o.redirect && o.tls_cert.empty())
    return makeError(WebErrc::kBadConfig,
                     "--http-redirect redirects to HTTPS: it needs --tls-cert and --tls-key");
  return {};
}

}  // namespace

Result<WebOptions> parseWebArgs(const std::vector<std::string>& args, bool* help) {
  auto o = cli::parseToolOptions<WebOptions, RawOptions>(args, help, webApp, defineOptions,
                                                         finishOptions);
  if (!o || (help && *help)) return o;
  if (auto checked = checkCombinations(*o); !checked) return checked.error();
  return o;
}

}  // namespace picksight::web
