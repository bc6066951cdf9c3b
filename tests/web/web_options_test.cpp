// picksight-web's options: endpoints, listen address, allow-list, errors.
#include <catch2/catch.hpp>

#include "picksight/web/web_options.hpp"
#include "temp_dir.hpp"

namespace picksight::web {

TEST_CASE("web options parse endpoints and the listen address", "[web]") {
  bool help = false;
  auto o = parseWebArgs({"--listen", "0.0.0.0:0", "--video-server", "tcp://a:1,tcp://a:2",
                         "--video-server", "tcp://b:1,tcp://b:2", "--vision-app",
                         "cam0,tcp://a:3,10.0.0.5:7000", "--allow", "10.0.0.0/8"},
                        &help);
  REQUIRE(o);
  CHECK(o->listen_host == "0.0.0.0");
  CHECK(o->listen_port == 0);
  REQUIRE(o->video_servers.size() == 2);
  CHECK(o->video_servers[1].control == "tcp://b:2");
  REQUIRE(o->vision_apps.size() == 1);
  CHECK(o->vision_apps[0].name == "cam0");
  CHECK(o->vision_apps[0].results == "tcp://a:3");
  CHECK(o->vision_apps[0].host == "10.0.0.5");
  CHECK(o->vision_apps[0].port == 7000);
  CHECK(!o->allow.allowsEveryone());
}

TEST_CASE("web options default to loopback port 8080", "[web]") {
  auto o = parseWebArgs({}, nullptr);
  REQUIRE(o);
  CHECK(o->listen_host == "127.0.0.1");
  CHECK(o->listen_port == 8080);
  CHECK(o->allow.allowsEveryone());
}

TEST_CASE("bad web options name the option", "[web]") {
  auto bad_app = parseWebArgs({"--vision-app", "cam0,tcp://a:3"}, nullptr);
  REQUIRE(!bad_app);
  CHECK(bad_app.error().message.find("--vision-app") != std::string::npos);
  auto bad_listen = parseWebArgs({"--listen", "localhost:99999"}, nullptr);
  REQUIRE(!bad_listen);
  CHECK(bad_listen.error().message.find("--listen") != std::string::npos);
  auto twice = parseWebArgs({"--vision-app", "a,none,h:1", "--vision-app", "a,none,h:2"}, nullptr);
  REQUIRE(!twice);
  CHECK(twice.error().message.find("twice") != std::string::npos);
  auto allow = parseWebArgs({"--allow", "10.0.0.0/99"}, nullptr);
  REQUIRE(!allow);
  CHECK(allow.error().message.find("--allow") != std::string::npos);
}

TEST_CASE("the web YAML file gives options and lists and the command line wins", "[web]") {
  test::TempDir dir;
  const std::string path = dir.write("web.yaml",
                                     "listen: 0.0.0.0:8081\n"
                                     "video-server:\n"
                                     "  - tcp://a:1,tcp://a:2\n"
                                     "  - tcp://b:1,tcp://b:2\n"
                                     "vision-app:\n  - cam0,tcp://a:3,127.0.0.1:5600\n"
                                     "allow: 10.0.0.0/8 127.0.0.1\n");
  auto o = parseWebArgs({"--config", path, "--listen", "127.0.0.1:9000"}, nullptr);
  INFO((o ? std::string() : o.error().message));
  REQUIRE(o);
  CHECK(o->listen_port == 9000);
  CHECK(o->video_servers.size() == 2);
  REQUIRE(o->vision_apps.size() == 1);
  CHECK(o->vision_apps[0].port == 5600);
  CHECK(!o->allow.allowsEveryone());

  auto bad = parseWebArgs({"--config", dir.write("bad.yaml", "listen: nowhere\n")}, nullptr);
  REQUIRE(!bad);
  CHECK(bad.error().message.find("listen") != std::string::npos);
  auto unknown = parseWebArgs({"--config", dir.write("unknown.yaml", "speed: 3\n")}, nullptr);
  REQUIRE(!unknown);
  CHECK(unknown.error().message.find("speed: unknown key") != std::string::npos);
}

}  // namespace picksight::web
