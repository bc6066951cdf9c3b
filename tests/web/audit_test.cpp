// The web HMI's audit trail: the rotated files and their bounds, damaged
// lines, and over real HTTP against a real cell, an engineer's changes with
// their before and after, an operator's refused ones, who may read and
// export the trail.
#include <chrono>
#include <filesystem>
#include <thread>

#include <nlohmann/json.hpp>

#include "picksight/common/atomic_file.hpp"
#include "picksight/web/access_policy.hpp"
#include "picksight/web/audit_trail.hpp"
#include "picksight/web/web_options.hpp"
#include "temp_dir.hpp"
#include "web_fixture.hpp"

namespace picksight::webtest {
namespace {
using namespace std::chrono_literals;
using e2e::VideoServerProcess;
using e2e::VisionProcess;
using nlohmann::json;
using web::AuditRecord;
using web::AuditTrail;

httplib::Result post(httplib::Client& client, const std::string& path, const json& body) {
  return postJson(client, path, body);
}

size_t fileSize(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  return ec ? 0 : static_cast<size_t>(size);
}

// The newest records of GET /api/audit as `client`.
json auditOf(httplib::Client& client, int limit = 100) {
  auto res = client.Get(("/api/audit?limit=" + std::to_string(limit)).c_str());
  REQUIRE(res);
  REQUIRE(res->status == 200);
  return json::parse(res->body);
}

// The first (newest) record matching every key of `match`; null if none.
json find(const json& records, const json& match) {
  for (const auto& r : records) {
    bool all = true;
    for (auto it = match.begin(); it != match.end() && all; ++it)
      all = r.contains(it.key()) && r[it.key()] == it.value();
    if (all) return r;
  }
  return nullptr;
}

}  // namespace

TEST_CASE("the audit trail rotates at its cap and never holds more than cap x files",
          "[web][audit]") {
  test::TempDir dir;
  const std::string path = (dir.path() / "audit.jsonl").string();
  const size_t cap = 16 * 1024;
  auto trail = AuditTrail::open({path, cap, 3});
  REQUIRE(trail);
  size_t most = 0;
  size_t largest = 0;
  for (int i = 0; i < 400; ++i) {
    AuditRecord r;
    r.user = "emil";
    r.action = "command";
    r.arguments = {{"line", "TOLERANCE 4 area_tolerance 0." + std::to_string(i)}};
    r.reply = std::string(i % 7 == 0 ? 5000 : 100, 'x');  // some cut to the field bound
    (*trail)->record(r);
    for (const char* suffix : {"", ".1", ".2"})
      largest = std::max(largest, fileSize(path + suffix));
    most = std::max(most, fileSize(path) + fileSize(path + ".1") + fileSize(path + ".2"));
  }
  CHECK(largest <= cap);
  CHECK(most <= 3 * cap);
  CHECK(most > 2 * cap);  // it did fill them
  CHECK(!std::filesystem::exists(path + ".3"));
  // The newest first, the oldest gone.
  auto read = (*trail)->newest(1000);
  CHECK(read.notes.empty());
  REQUIRE(read.records.size() > 50);
  CHECK(read.records.front()["arguments"]["line"] == "TOLERANCE 4 area_tolerance 0.399");
  CHECK(read.records.size() < 400);
  CHECK(read.records[1]["arguments"]["line"] == "TOLERANCE 4 area_tolerance 0.398");
  CHECK((*trail)->newest(5).records.size() == 5);
  // A long field is cut, and says so.
  AuditRecord long_reply;
  long_reply.reply = std::string(5000, 'y');
  const std::string line = AuditTrail::line(long_reply);
  CHECK(line.size() < web::kMaxRecordBytes);
  CHECK_THAT(line, Catch::Contains("5000 bytes"));
  // The trail is bounded as a whole too.
  CHECK(web::parseWebArgs({"--audit-max-kib", "16384", "--audit-files", "4"}, nullptr));
  auto too_much = web::parseWebArgs({"--audit-max-kib", "16384", "--audit-files", "5"}, nullptr);
  REQUIRE_FALSE(too_much);
  CHECK_THAT(too_much.error().message, Catch::Contains("65536 KiB"));
}

TEST_CASE("a damaged audit line is skipped with a note and a cut last line is closed",
          "[web][audit]") {
  test::TempDir dir;
  const std::string path = (dir.path() / "audit.jsonl").string();
  REQUIRE(writeFileAtomically(path,
                              "{\"time\":\"2026-01-01T00:00:00.000Z\",\"action\":\"login\"}\n"
                              "garbage that is not JSON\n"
                              "[1,2]\n"
                              "{\"time\":\"2026-01-01T00:00:01.000Z\",\"action\":\"cut"));
  auto trail = AuditTrail::open({path, 64 * 1024, 2});
  REQUIRE(trail);
  AuditRecord record;
  record.user = "emil";
  record.action = "command";
  (*trail)->record(record);
  auto read = (*trail)->newest(10);
  REQUIRE(read.records.size() == 2);
  CHECK(read.records[0]["user"] == "emil");
  CHECK(read.records[1]["action"] == "login");
  REQUIRE(read.notes.size() == 3);
  CHECK_THAT(read.notes[0], Catch::Contains("audit.jsonl line 2"));
  CHECK_THAT(read.notes[2], Catch::Contains("audit.jsonl line 4"));
}

TEST_CASE(
    "an engineer's changes are in the audit trail with the user and the values before and after",
    "[web][audit]") {
  test::TempDir dir;
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=1", "--fps", "10"});
  VisionProcess vision(server);
  const std::string audit_file = (dir.path() / "audit.jsonl").string();
  WebProcess web({"--video-server", server.frames + "," + server.control, "--vision-app",
                  "cam0,none,127.0.0.1:" + std::to_string(vision.robot_port), "--users",
                  (dir.path() / "users.json").string()});
  auto admin = web.client();
  REQUIRE(post(admin, "/api/users",
               {{"name", "olga"}, {"role", "operator"}, {"password", "operator-olga"}})
              ->status == 200);
  REQUIRE(post(admin, "/api/users",
               {{"name", "emil"}, {"role", "engineer"}, {"password", "engineer-emil"}})
              ->status == 200);
  auto emil = web.as(web.login("emil", "engineer-emil"));
  auto olga = web.as(web.login("olga", "operator-olga"));
  REQUIRE(json::parse(post(emil, "/api/apps/cam0/command", {{"line", "LEARN 4"}})->body)["reply"]
              .get<std::string>()
              .rfind("OK 4 ", 0) == 0);
  auto res = post(emil, "/api/apps/cam0/command", {{"line", "TOLERANCE 4 area_tolerance 0.3"}});
  REQUIRE(res);
  REQUIRE(res->status == 200);
  // A LOCATE is no change: not recorded.
  REQUIRE(post(olga, "/api/apps/cam0/command", {{"line", "LOCATE 4"}})->status == 200);
  // Refused for the role: recorded as refused, and nothing changed.
  REQUIRE(post(olga, "/api/apps/cam0/command", {{"line", "FORGET 4"}})->status == 403);
  REQUIRE(post(olga, "/api/cameras/cam0/close", json::object())->status == 403);
  auto robot = vision.connect();
  CHECK(robot.request("MODELS", 5s)->rfind("OK 1 4 ", 0) == 0);
  // A camera setting, read before and after.
  res = post(emil, "/api/cameras/cam0/feature", {{"name", "Parts"}, {"value", "2"}});
  REQUIRE(res);
  CHECK(res->status == 200);
  CHECK(web.login("emil", "not-the-password").empty());

  const json trail = auditOf(admin);
  const json& records = trail["records"];
  INFO(trail.dump(1));
  CHECK(trail["file"] == audit_file);
  CHECK(trail["notes"].empty());
  const json tolerance = find(records, {{"action", "command"}, {"user", "emil"}});
  REQUIRE(!tolerance.is_null());
  CHECK(tolerance["role"] == "engineer");
  CHECK(tolerance["address"] == "127.0.0.1");
  CHECK(tolerance["target"] == "cam0");
  CHECK(tolerance["arguments"]["line"] == "TOLERANCE 4 area_tolerance 0.3");
  CHECK(tolerance["outcome"] == "ok");
  CHECK_THAT(tolerance["reply"].get<std::string>(), Catch::Contains("area_tolerance=0.3"));
  CHECK_THAT(tolerance["before"].get<std::string>(), !Catch::Contains("area_tolerance=0.3"));
  CHECK_THAT(tolerance["after"].get<std::string>(), Catch::Contains("area_tolerance=0.3"));
  const std::string time = tolerance["time"];
  CHECK(time.size() == 24);
  CHECK(time.back() == 'Z');
  CHECK(time[10] == 'T');
  CHECK(!find(records, {{"arguments", {{"line", "LEARN 4"}}}, {"outcome", "ok"}}).is_null());
  CHECK(find(records, {{"arguments", {{"line", "LOCATE 4"}}}}).is_null());
  const json forget = find(records, {{"user", "olga"}, {"action", "command"}});
  REQUIRE(!forget.is_null());
  CHECK(forget["outcome"] == "refused");
  CHECK(forget["role"] == "operator");
  CHECK(forget["status"] == 403);
  const json close = find(records, {{"user", "olga"}, {"action", "request"}});
  REQUIRE(!close.is_null());
  CHECK(close["target"] == "/api/cameras/cam0/close");
  CHECK(close["outcome"] == "refused");
  const json feature = find(records, {{"action", "camera.feature"}});
  REQUIRE(!feature.is_null());
  CHECK(feature["user"] == "emil");
  CHECK(feature["before"]["value"] == "1");
  CHECK(feature["after"]["value"] == "2");
  const json users = find(records, {{"action", "user.set"}, {"target", "emil"}});
  REQUIRE(!users.is_null());
  CHECK(users["user"] == "admin");
  CHECK(users["after"]["role"] == "engineer");
  CHECK(users["arguments"]["password"] == "(set)");
  const json failed = find(records, {{"action", "login"}, {"outcome", "refused"}});
  REQUIRE(!failed.is_null());
  CHECK(failed["arguments"]["user"] == "emil");
  CHECK(!find(records, {{"action", "login"}, {"user", "olga"}, {"outcome", "ok"}}).is_null());
  // No password anywhere in the file.
  const auto text = readFile(audit_file);
  REQUIRE(text);
  for (const char* secret : {"engineer-emil", "operator-olga", "not-the-password"})
    CHECK(text->find(secret) == std::string::npos);

  // An engineer reads the trail, an operator does not; only an admin exports.
  CHECK(emil.Get("/api/audit")->status == 200);
  CHECK(olga.Get("/api/audit")->status == 403);
  CHECK(emil.Get("/api/audit.jsonl")->status == 403);
  CHECK(admin.Get("/api/audit?limit=0")->status == 400);
  CHECK(admin.Get("/api/audit?limit=1001")->status == 400);
  CHECK(auditOf(admin, 2)["records"].size() == 2);
  auto exported = admin.Get("/api/audit.jsonl");
  REQUIRE(exported);
  CHECK(exported->status == 200);
  CHECK(exported->body == *readFile(audit_file));
  CHECK_THAT(exported->get_header_value("Content-Disposition"), Catch::Contains("attachment"));
}

TEST_CASE("the web's audit file rotates at its cap and skips a damaged line", "[web][audit]") {
  test::TempDir dir;
  const std::string audit_file = (dir.path() / "trail.jsonl").string();
  const size_t cap = 16 * 1024;
  // Both files nearly full of old records, one line damaged.
  std::string old;
  while (old.size() < cap - 400)
    old += R"({"time":"2026-01-01T00:00:00.000Z","action":"old","reply":")" +
           std::string(200, 'o') + "\"}\n";
  REQUIRE(writeFileAtomically(audit_file + ".1", old));
  REQUIRE(writeFileAtomically(audit_file, "not json at all\n" + old));
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  auto args = videoServerArgs(server);
  args.insert(args.end(),
              {"--audit-file", audit_file, "--audit-max-kib", "16", "--audit-files", "2"});
  WebProcess web(args);  // its admin's login is the first record
  auto admin = web.client();
  for (int i = 0; i < 3; ++i)
    REQUIRE(post(admin, "/api/cameras/cam0/feature", {{"name", "Parts"}, {"value", "1"}})->status ==
            200);
  CHECK(fileSize(audit_file) <= cap);
  CHECK(fileSize(audit_file + ".1") <= cap);
  CHECK(!std::filesystem::exists(audit_file + ".2"));
  const json trail = auditOf(admin, 1000);
  const json& records = trail["records"];
  REQUIRE(records.size() >= 4);
  CHECK(records[0]["action"] == "camera.feature");
  CHECK(records[3]["action"] == "login");
  // The damaged line rotated into .1 and is skipped with a note.
  REQUIRE(trail["notes"].size() == 1);
  CHECK_THAT(trail["notes"][0].get<std::string>(), Catch::Contains("trail.jsonl.1 line 1"));
  // The first old file is gone: records of one file of old ones at most.
  size_t olds = 0;
  for (const auto& r : records) olds += r["action"] == "old" ? 1 : 0;
  CHECK(olds > 0);
  CHECK(olds * 200 < cap);
}

}  // namespace picksight::webtest

namespace picksight::web {

TEST_CASE("a teach preview needs an engineer but is not a change", "[web][audit]") {
  // TRYLEARN learns on a fresh frame and stores nothing: the trail, which
  // records changes, would fill with previews.
  CHECK(roleForCommand("TRYLEARN 3 bracket") == Role::kEngineer);
  CHECK_FALSE(changesCell("TRYLEARN 3 bracket"));
  CHECK_FALSE(changesCell("trylearn,3"));
  CHECK(changesCell("LEARN 3 bracket"));
  CHECK(changesCell("UNDO"));
  CHECK_FALSE(changesCell("LOCATE 1"));
  CHECK_FALSE(changesCell("TOLERANCE 4"));
  CHECK_FALSE(changesCell("VISION"));
  CHECK(changesCell("VISION polarity light"));
}

TEST_CASE("a change's read-back line is the read of what it changes", "[web][audit]") {
  CHECK(readBackLine("TOLERANCE 4 area_tolerance 0.3") == "TOLERANCE 4");
  CHECK(readBackLine("grasp 2 add 0 0 0") == "GRASP 2 LIST");
  CHECK(readBackLine("GRIPPER,3,CLEAR") == "GRIPPER 3 LIST");
  CHECK(readBackLine("EXPOSURE 900") == "EXPOSURE");
  CHECK(readBackLine("CAMMODE trigger") == "CAMMODE");
  CHECK(readBackLine("vision polarity light level 90") == "VISION");
  CHECK(readBackLine("VISION RESET") == "VISION");
  // Reads, and changes without a cheap read.
  for (const char* line : {"TOLERANCE 4", "GRASP 2 LIST", "EXPOSURE", "LOCATE 1", "LEARN 4",
                           "CALCAM 5", "TOLERANCE x area_tolerance 1", "FORGET 4", "VISION"}) {
    CAPTURE(line);
    CHECK_FALSE(readBackLine(line));
  }
}

}  // namespace picksight::web

namespace picksight::webtest {

TEST_CASE("a change made on the robot port is in the web's audit trail with the robot's address",
          "[web][audit]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=1", "--fps", "10"});
  VisionProcess vision(server);
  REQUIRE(!vision.results_endpoint.empty());
  WebProcess web(
      {"--video-server", server.frames + "," + server.control, "--vision-app",
       "cam0," + vision.results_endpoint + ",127.0.0.1:" + std::to_string(vision.robot_port)});
  auto admin = web.client();
  auto robot = vision.connect();
  // The web's subscription has reached the app once a result of ours
  // arrives (a SUB socket joins a moment after it connects).
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (true) {
    REQUIRE(robot.request("LOCATE ALL", 5s));
    const json apps = json::parse(admin.Get("/api/apps")->body);
    if (apps[0].value("last_result_id", 0) > 0) break;
    REQUIRE(std::chrono::steady_clock::now() < deadline);
    std::this_thread::sleep_for(100ms);
  }
  REQUIRE(robot.request("LEARN 4", 5s)->rfind("OK 4 ", 0) == 0);
  // The page's own change: recorded by the web once, with its user, not a
  // second time from the app's stream.
  auto res = post(admin, "/api/apps/cam0/command", {{"line", "TOLERANCE 4 area_tolerance 0.3"}});
  REQUIRE(res);
  REQUIRE(res->status == 200);
  // Refused (no such model) and read-only lines: nothing changed, not recorded.
  CHECK(robot.request("FORGET 77", 5s)->rfind("ERROR", 0) == 0);
  CHECK(robot.request("MODELS", 5s)->rfind("OK 1 4", 0) == 0);
  const std::string tolerance = *robot.request("TOLERANCE 4 area_tolerance 0.25", 5s);
  REQUIRE(tolerance.rfind("OK", 0) == 0);

  // The app publishes each change after its reply: the trail has it soon
  // after, in the order made.
  const std::string peer = robot.localEndpoint();
  REQUIRE(peer.rfind("127.0.0.1:", 0) == 0);
  json records;
  const auto until = std::chrono::steady_clock::now() + 20s;
  while (find(records, {{"arguments", {{"line", "TOLERANCE 4 area_tolerance 0.25"}}}}).is_null()) {
    REQUIRE(std::chrono::steady_clock::now() < until);
    std::this_thread::sleep_for(100ms);
    records = auditOf(admin, 1000)["records"];
  }
  INFO(records.dump(1));
  const json changed =
      find(records, {{"arguments", {{"line", "TOLERANCE 4 area_tolerance 0.25"}}}});
  CHECK(changed["user"] == "robot " + peer);
  CHECK(changed["role"] == "robot port");
  CHECK(changed["address"] == "127.0.0.1");
  CHECK(changed["action"] == "command");
  CHECK(changed["target"] == "cam0");
  CHECK(changed["outcome"] == "ok");
  CHECK(changed["reply"] == tolerance);
  const json learned = find(records, {{"arguments", {{"line", "LEARN 4"}}}});
  REQUIRE(!learned.is_null());
  CHECK(learned["user"] == "robot " + peer);
  CHECK(learned["reply"].get<std::string>().rfind("OK 4 ", 0) == 0);
  int page_changes = 0;
  for (const auto& r : records)
    if (r.value("arguments", json::object()).value("line", "") ==
        "TOLERANCE 4 area_tolerance 0.3") {
      ++page_changes;
      CHECK(r["user"] == "admin");
    }
  CHECK(page_changes == 1);
  CHECK(find(records, {{"arguments", {{"line", "FORGET 77"}}}}).is_null());
  CHECK(find(records, {{"arguments", {{"line", "MODELS"}}}}).is_null());
  CHECK(find(records, {{"arguments", {{"line", "LOCATE ALL"}}}}).is_null());
  // A change that worked on no frame is no result for the page to draw.
  const json latest = json::parse(admin.Get("/api/results/cam0/latest")->body);
  CHECK(latest["request"] == "LEARN");
}

}  // namespace picksight::webtest
