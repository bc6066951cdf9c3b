// The web HMI's users, sessions, login limit and the role each request
// needs, without a server: argon2id hashes in an atomically written file,
// sessions that expire, an operator who cannot teach.
#include <chrono>
#include <thread>

#include <catch2/catch.hpp>

#include "picksight/common/atomic_file.hpp"
#include "picksight/web/access_policy.hpp"
#include "picksight/web/sessions.hpp"
#include "picksight/web/user_store.hpp"
#include "temp_dir.hpp"

namespace picksight::web {
using namespace std::chrono_literals;

TEST_CASE("users are stored with argon2id hashes and checked against them", "[web][users]") {
  test::TempDir dir;
  const std::string path = (dir.path() / "users.json").string();
  {
    auto store = UserStore::open(path);
    REQUIRE(store);
    CHECK(store->empty());
    REQUIRE(store->set("admin", Role::kAdmin, "correct horse battery"));
    REQUIRE(store->set("op", Role::kOperator, "operator-pass"));
    CHECK(store->verify("admin", "correct horse battery") == Role::kAdmin);
    CHECK_FALSE(store->verify("admin", "correct horse batterY"));
    CHECK_FALSE(store->verify("nobody", "correct horse battery"));
    CHECK(store->verify("op", "operator-pass") == Role::kOperator);
    // Bounds: names, password lengths; the last admin stays.
    CHECK_FALSE(store->set("bad name", Role::kOperator, "long enough"));
    CHECK_FALSE(store->set("short", Role::kOperator, "seven77"));
    CHECK_FALSE(store->remove("admin"));
    CHECK_FALSE(store->set("admin", Role::kOperator, "correct horse battery"));
    CHECK_FALSE(store->remove("ghost"));
  }
  const auto text = readFile(path);
  REQUIRE(text);
  CHECK(text->find("$argon2id$") != std::string::npos);
  CHECK(text->find("correct horse battery") == std::string::npos);
  CHECK(text->find("operator-pass") == std::string::npos);
  // A second start reads the same users.
  auto again = UserStore::open(path);
  REQUIRE(again);
  CHECK(again->list().size() == 2);
  CHECK(again->verify("op", "operator-pass") == Role::kOperator);
  REQUIRE(again->remove("op"));
  CHECK_FALSE(again->verify("op", "operator-pass"));
  // A damaged file is an error naming it, never an empty user list.
  REQUIRE(writeFileAtomically(path, R"({"users":[{"name":"x","role":"root","hash":"plain"}]})"));
  auto damaged = UserStore::open(path);
  REQUIRE_FALSE(damaged);
  CHECK_THAT(damaged.error().message, Catch::Contains(path));
}

TEST_CASE("a first password is random and long", "[web][users]") {
  const std::string a = UserStore::randomPassword();
  const std::string b = UserStore::randomPassword();
  CHECK(a.size() == 16);
  CHECK(a != b);
}

TEST_CASE("a session ends at its idle timeout and on logout", "[web][users]") {
  Sessions sessions(1s, 3600s);
  const std::string token = sessions.create({"op", Role::kOperator});
  CHECK(token.size() == 64);
  auto found = sessions.find(token);
  REQUIRE(found);
  CHECK(found->user == "op");
  CHECK_FALSE(sessions.find(token.substr(0, 63) + (token.back() == '0' ? "1" : "0")));
  std::this_thread::sleep_for(1500ms);
  CHECK_FALSE(sessions.find(token));
  const std::string other = sessions.create({"eng", Role::kEngineer});
  REQUIRE(sessions.find(other));
  sessions.remove(other);
  CHECK_FALSE(sessions.find(other));
  const std::string third = sessions.create({"eng", Role::kEngineer});
  sessions.removeUser("eng");
  CHECK_FALSE(sessions.find(third));
}

TEST_CASE("logins from an address are limited after 5 failures", "[web][users]") {
  LoginLimiter limiter(5, 60s);
  for (int i = 0; i < 4; ++i) limiter.failed("10.0.0.9");
  CHECK_FALSE(limiter.blocked("10.0.0.9"));
  limiter.failed("10.0.0.9");
  auto wait = limiter.blocked("10.0.0.9");
  REQUIRE(wait);
  CHECK(wait->count() > 0);
  CHECK(wait->count() <= 61);
  CHECK_FALSE(limiter.blocked("10.0.0.10"));
  limiter.succeeded("10.0.0.9");
  CHECK_FALSE(limiter.blocked("10.0.0.9"));
}

TEST_CASE("an operator may locate and read but not teach or calibrate", "[web][users]") {
  for (const char* line :
       {"LOCATE 1", "locate all", "WHY", "STATUS", "MODELS", "LIST", "RESIDUALS", "TOLERANCE 3",
        "GRASP 2 LIST", "GRIPPER 2 list", "EXPOSURE", "ROI", "CAMMODE", "VISION", "vision"}) {
    CAPTURE(line);
    CHECK(roleForCommand(line) == Role::kOperator);
  }
  for (const char* line :
       {"LEARN 4", "FORGET 4", "TOLERANCE 3 area_tolerance 0.2", "GRASP 2 ADD 0 0 0",
        "GRASP 2 CLEAR", "GRIPPER 2 FINGER 1 2 3 4", "CALCAM 5", "STORE 1 2", "DELETE 3", "COMPUTE",
        "CLEARCAL", "EXPOSURE 1000", "ROI 0 0 8 8", "CAMMODE trigger", "SOMETHINGNEW",
        "GRASP,2,ADD,0,0,0", "VISION polarity light", "VISION RESET"}) {
    CAPTURE(line);
    CHECK(roleForCommand(line) == Role::kEngineer);
  }
  CHECK(roleForCameraAction("trigger") == Role::kOperator);
  for (const char* action : {"roi", "size", "mode", "feature", "open", "close", "target"})
    CHECK(roleForCameraAction(action) == Role::kEngineer);
}

TEST_CASE("an operator may read and replay the filmstrip, an engineer exports it",
          "[web][users][filmstrip]") {
  for (const char* line :
       {"FILMSTRIP", "FILMSTRIP 10 FAILURES", "filmstrip show 3", "FILMSTRIP IMAGE 3 160",
        "FILMSTRIP STATUS", "REPLAY 3", "replay 3 all"}) {
    CAPTURE(line);
    CHECK(roleForCommand(line) == Role::kOperator);
  }
  CHECK(roleForCommand("FILMSTRIP EXPORT run1") == Role::kEngineer);
  CHECK(roleForCommand("filmstrip,export,run1") == Role::kEngineer);
}

}  // namespace picksight::web
