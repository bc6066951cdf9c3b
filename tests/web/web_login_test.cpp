// picksight-web's users over HTTP: nothing but the page and its login
// without a session, an operator who can locate but not teach or close the
// camera, logout and expiry, the login limit, the users file kept across
// restarts.
#include <sys/stat.h>
#include <sys/wait.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "picksight/common/atomic_file.hpp"
#include "raw_http.hpp"
#include "temp_dir.hpp"
#include "web_fixture.hpp"

namespace picksight::webtest {
namespace {
using namespace std::chrono_literals;
using e2e::VideoServerProcess;
using e2e::VisionProcess;
using nlohmann::json;
using tool_support::Subprocess;

httplib::Result post(httplib::Client& client, const std::string& path, const json& body) {
  return postJson(client, path, body);
}

}  // namespace

TEST_CASE("without a session only the page and the login answer", "[web][users]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  WebProcess web(videoServerArgs(server));
  REQUIRE(web.admin_password.size() == 16);
  auto anonymous = web.anonymousClient();
  for (const char* path : {"/", "/static/app.js"}) {
    auto res = anonymous.Get(path);
    REQUIRE(res);
    CHECK(res->status == 200);
  }
  for (const char* path : {"/api/cameras", "/api/apps", "/snapshot/cam0.png", "/frame/cam0.jpg",
                           "/events", "/metrics", "/api/users"}) {
    CAPTURE(path);
    auto res = anonymous.Get(path);
    REQUIRE(res);
    CHECK(res->status == 401);
  }
  auto who = anonymous.Get("/api/session");
  REQUIRE(who);
  CHECK(who->status == 200);
  CHECK(json::parse(who->body)["user"].is_null());
  auto res = post(anonymous, "/api/cameras/cam0/close", json::object());
  REQUIRE(res);
  CHECK(res->status == 401);
  // The admin's session, from the printed password.
  res = web.as(web.cookie).Get("/api/session");
  REQUIRE(res);
  CHECK(res->status == 200);
  CHECK(json::parse(res->body)["role"] == "admin");
}

TEST_CASE("the session cookie is HttpOnly and SameSite=Strict and ends at logout", "[web][users]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  WebProcess web(videoServerArgs(server));
  auto anonymous = web.anonymousClient();
  auto res = post(anonymous, "/api/login", {{"user", "admin"}, {"password", web.admin_password}});
  REQUIRE(res);
  REQUIRE(res->status == 200);
  const std::string set = res->get_header_value("Set-Cookie");
  CHECK(set.find("HttpOnly") != std::string::npos);
  CHECK(set.find("SameSite=Strict") != std::string::npos);
  CHECK(set.find("Max-Age=") != std::string::npos);
  auto session = web.as(set.substr(0, set.find(';')));
  CHECK(session.Get("/api/cameras")->status == 200);
  CHECK(post(session, "/api/logout", json::object())->status == 200);
  CHECK(session.Get("/api/cameras")->status == 401);
  // The other session (the fixture's) is untouched.
  CHECK(web.client().Get("/api/cameras")->status == 200);
  res = post(anonymous, "/api/login", {{"user", "admin"}, {"password", "not the password"}});
  REQUIRE(res);
  CHECK(res->status == 401);
}

TEST_CASE("an operator locates but cannot teach nor close the camera nor manage users",
          "[web][users]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=1", "--fps", "10"});
  VisionProcess vision(server);
  WebProcess web({"--video-server", server.frames + "," + server.control, "--vision-app",
                  "cam0,none,127.0.0.1:" + std::to_string(vision.robot_port)});
  auto admin = web.client();
  REQUIRE(post(admin, "/api/users",
               {{"name", "olga"}, {"role", "operator"}, {"password", "operator-olga"}})
              ->status == 200);
  REQUIRE(post(admin, "/api/users",
               {{"name", "emil"}, {"role", "engineer"}, {"password", "engineer-emil"}})
              ->status == 200);
  auto olga = web.as(web.login("olga", "operator-olga"));
  auto res = post(olga, "/api/apps/cam0/command", {{"line", "LOCATE 1"}});
  REQUIRE(res);
  CHECK(res->status == 200);
  for (const char* line : {"LEARN 4", "FORGET 4", "TOLERANCE 4 area_tolerance 0.2", "CALCAM 5",
                           "STORE 1 2", "COMPUTE", "CLEARCAL", "GRASP 4 ADD 0 0 0"}) {
    CAPTURE(line);
    res = post(olga, "/api/apps/cam0/command", {{"line", line}});
    REQUIRE(res);
    CHECK(res->status == 403);
    CHECK_THAT(json::parse(res->body)["error"].get<std::string>(), Catch::Contains("engineer"));
  }
  res = post(olga, "/api/cameras/cam0/close", json::object());
  REQUIRE(res);
  CHECK(res->status == 403);
  CHECK(olga.Get("/api/users")->status == 403);
  CHECK(post(olga, "/api/users", {{"name", "olga"}, {"role", "admin"}, {"password", "x12345678"}})
            ->status == 403);
  // Nothing changed; the engineer teaches.
  auto robot = vision.connect();
  CHECK(*robot.request("MODELS", 5s) == "OK 0");
  auto emil = web.as(web.login("emil", "engineer-emil"));
  res = post(emil, "/api/apps/cam0/command", {{"line", "LEARN 4"}});
  REQUIRE(res);
  CHECK(res->status == 200);
  CHECK(json::parse(res->body)["reply"].get<std::string>().rfind("OK 4 ", 0) == 0);
  CHECK(emil.Get("/api/users")->status == 403);
}

TEST_CASE(
    "an admin adds users and changes a role and a password and removes one but never the last "
    "admin",
    "[web][users][audit]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  WebProcess web(videoServerArgs(server));
  auto admin = web.client();
  const auto users = [&](httplib::Client& as) {
    std::map<std::string, std::string> roles;
    for (const auto& u : json::parse(as.Get("/api/users")->body))
      roles[u["name"].get<std::string>()] = u["role"].get<std::string>();
    return roles;
  };
  const auto error = [](const httplib::Result& res) {
    return json::parse(res->body)["error"].get<std::string>();
  };
  REQUIRE(post(admin, "/api/users",
               {{"name", "ida"}, {"role", "operator"}, {"password", "operator-ida"}, {"new", true}})
              ->status == 200);
  // "new": an existing name is a conflict, nothing replaced.
  auto res = post(admin, "/api/users",
                  {{"name", "ida"}, {"role", "admin"}, {"password", "another-one"}, {"new", true}});
  CHECK(res->status == 409);
  CHECK_THAT(error(res), Catch::Contains("exists"));
  CHECK(users(admin)["ida"] == "operator");
  const std::string ida_cookie = web.login("ida", "operator-ida");
  auto ida = web.as(ida_cookie);
  CHECK(ida.Get("/api/cameras")->status == 200);
  // Only an admin changes users.
  CHECK(post(ida, "/api/users/ida/role", {{"role", "admin"}})->status == 403);

  // A new role keeps the password and ends the user's sessions.
  REQUIRE(post(admin, "/api/users/ida/role", {{"role", "engineer"}})->status == 200);
  CHECK(users(admin)["ida"] == "engineer");
  CHECK(ida.Get("/api/cameras")->status == 401);
  CHECK(!web.login("ida", "operator-ida").empty());
  // A new password keeps the role.
  REQUIRE(post(admin, "/api/users/ida/password", {{"password", "engineer-ida"}})->status == 200);
  CHECK(web.login("ida", "operator-ida").empty());
  CHECK(!web.login("ida", "engineer-ida").empty());
  CHECK(users(admin)["ida"] == "engineer");
  // Bad input: a clear 4xx, nothing changed.
  res = post(admin, "/api/users/ida/role", {{"role", "root"}});
  CHECK(res->status == 400);
  CHECK_THAT(error(res), Catch::Contains("operator, engineer or admin"));
  res = post(admin, "/api/users/ida/password", {{"password", "short"}});
  CHECK(res->status == 400);
  CHECK_THAT(error(res), Catch::Contains("8 to 256"));
  CHECK(post(admin, "/api/users/nobody/role", {{"role", "operator"}})->status == 404);
  CHECK(!web.login("ida", "engineer-ida").empty());

  // The last admin can neither lose the role nor go.
  res = post(admin, "/api/users/admin/role", {{"role", "engineer"}});
  CHECK(res->status == 409);
  CHECK_THAT(error(res), Catch::Contains("last admin"));
  res = post(admin, "/api/users/admin/delete", json::object());
  CHECK(res->status == 409);
  CHECK_THAT(error(res), Catch::Contains("last admin"));
  CHECK(users(admin)["admin"] == "admin");
  CHECK(admin.Get("/api/users")->status == 200);  // that session goes on
  // With a second admin, the first may step down.
  REQUIRE(post(admin, "/api/users/ida/role", {{"role", "admin"}})->status == 200);
  auto ida_admin = web.as(web.login("ida", "engineer-ida"));
  REQUIRE(post(admin, "/api/users/admin/role", {{"role", "engineer"}})->status == 200);
  CHECK(admin.Get("/api/users")->status == 401);  // its own session ended with the role
  CHECK(users(ida_admin)["admin"] == "engineer");
  REQUIRE(post(ida_admin, "/api/users/admin/delete", json::object())->status == 200);
  CHECK(users(ida_admin).count("admin") == 0);

  // Each change in the trail, by whom, with the role before and after;
  // never a password.
  auto trail = ida_admin.Get("/api/audit?limit=100");
  REQUIRE(trail);
  REQUIRE(trail->status == 200);
  CHECK(trail->body.find("operator-ida") == std::string::npos);
  CHECK(trail->body.find("engineer-ida") == std::string::npos);
  const json records = json::parse(trail->body)["records"];
  std::vector<std::string> seen;
  for (const auto& r : records) {
    const std::string action = r.value("action", "");
    if (action.rfind("user.", 0) != 0) continue;
    seen.push_back(action + " " + r.value("target", "") + " " + r.value("user", "") + " " +
                   r.value("outcome", "") + " " + r.value("before", json()).dump() + " " +
                   r.value("after", json()).dump());
  }
  std::reverse(seen.begin(), seen.end());  // oldest first
  const std::vector<std::string> expected = {
      R"x(user.add ida admin ok "(no such user)" {"role":"operator"})x",
      R"x(user.add ida admin error {"role":"operator"} null)x",
      R"x(user.role ida admin ok {"role":"operator"} {"role":"engineer"})x",
      R"x(user.password ida admin ok {"role":"engineer"} {"role":"engineer"})x",
      R"x(user.password ida admin error {"role":"engineer"} null)x",
      R"x(user.role nobody admin error "(no such user)" null)x",
      R"x(user.role admin admin error {"role":"admin"} null)x",
      R"x(user.delete admin admin error {"role":"admin"} null)x",
      R"x(user.role ida admin ok {"role":"engineer"} {"role":"admin"})x",
      R"x(user.role admin admin ok {"role":"admin"} {"role":"engineer"})x",
      R"x(user.delete admin ida ok {"role":"engineer"} "(removed)")x",
  };
  CHECK(seen == expected);
}

TEST_CASE("a session ends after --session-timeout without a request", "[web][users]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  auto args = videoServerArgs(server);
  args.insert(args.end(), {"--session-timeout", "1"});
  WebProcess web(args);
  auto admin = web.client();
  CHECK(admin.Get("/api/cameras")->status == 200);
  std::this_thread::sleep_for(1500ms);
  CHECK(admin.Get("/api/cameras")->status == 401);
}

TEST_CASE("five failed logins from an address hold its next ones for a minute", "[web][users]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  WebProcess web(videoServerArgs(server));
  auto anonymous = web.anonymousClient();
  for (int i = 0; i < 5; ++i)
    CHECK(post(anonymous, "/api/login",
               {{"user", "admin"}, {"password", "guess" + std::to_string(i)}})
              ->status == 401);
  auto res = post(anonymous, "/api/login", {{"user", "admin"}, {"password", web.admin_password}});
  REQUIRE(res);
  CHECK(res->status == 429);
  CHECK(!res->get_header_value("Retry-After").empty());
}

TEST_CASE("the users file keeps the users and no new password is printed", "[web][users]") {
  test::TempDir dir;
  const std::string users = (dir.path() / "users.json").string();
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  auto args = videoServerArgs(server);
  args.insert(args.end(), {"--users", users});
  std::string password;
  {
    WebProcess first(args);
    password = first.admin_password;
    REQUIRE(password.size() == 16);
  }
  const auto text = readFile(users);
  REQUIRE(text);
  CHECK(text->find("$argon2id$") != std::string::npos);
  CHECK(text->find(password) == std::string::npos);
  WebProcess second(args);
  CHECK(second.admin_password.empty());
  CHECK(!second.login("admin", password).empty());
}

}  // namespace picksight::webtest

namespace picksight::webtest {

TEST_CASE("the installer's first admin gets a random password in a 0600 file", "[web][users]") {
  test::TempDir dir;
  const std::string users = (dir.path() / "users.json").string();
  const std::string password_file = (dir.path() / "admin-password").string();
  const auto run = [&](const std::string& out) {
    Subprocess web({e2e::binPath("picksight-web"), "--users", users, "--first-admin", out});
    const auto status = web.wait(std::chrono::seconds(20));
    REQUIRE(status);
    REQUIRE(WIFEXITED(*status));
    return WEXITSTATUS(*status);
  };
  // A password file that exists is never overwritten, and nothing is made.
  const std::string taken = dir.write("taken", "someone's\n");
  CHECK(run(taken) == 1);
  CHECK(!std::filesystem::exists(users));
  CHECK(*readFile(taken) == "someone's\n");

  REQUIRE(run(password_file) == 0);
  struct stat info {};
  REQUIRE(::stat(password_file.c_str(), &info) == 0);
  CHECK((info.st_mode & 0777) == 0600);
  const auto text = readFile(password_file);
  REQUIRE(text);
  const std::string password = text->substr(0, text->find('\n'));
  CHECK(password.size() == 20);
  CHECK(readFile(users)->find(password) == std::string::npos);
  // Users exist: a second run changes nothing and writes no password.
  const std::string second = (dir.path() / "second").string();
  CHECK(run(second) == 0);
  CHECK(!std::filesystem::exists(second));
  // The server starts with that admin and prints no password.
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  auto args = videoServerArgs(server);
  args.insert(args.end(), {"--users", users});
  WebProcess web(args);
  CHECK(web.admin_password.empty());
  CHECK(!web.login("admin", password).empty());
}

}  // namespace picksight::webtest
