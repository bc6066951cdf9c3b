// picksight::cli: what a tool's user sees of its options (the help, the
// messages naming the option at fault) and the --config file read through
// the same declarations.
#include <catch2/catch.hpp>

#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "picksight/cli/config_file.hpp"
#include "temp_dir.hpp"

using namespace picksight;
using picksight::test::TempDir;

namespace {

// A tool's options as the services declare theirs: values into Options,
// checked words into Raw, --config through Raw::config_file.
struct Options {
  int count = 3;
  double scale = 0.5;
  bool quiet = false;
  std::vector<std::string> peers;
  std::string mode = "fast";
  std::string server_key;
  std::string key;
};

struct Raw {
  std::string config_file;
};

cli::App makeApp() { return cli::App("A tool for the tests.", "tool"); }

void define(cli::App& app, Options& o, Raw& raw) {
  app.setHelpFlag("-h,--help", "print this help");
  app.addOption("--config", raw.config_file, "options from a YAML file")->typeName("FILE");
  app.addOption("--count", o.count, "how many")
      ->typeName("N")
      ->check(cli::range(1, 10))
      ->showDefault();
  app.addOption("--scale", o.scale, "how much")->check(cli::range(0.05, 1.0));
  app.addFlag("--quiet", o.quiet, "say less");
  app.addOption("--peer", o.peers, "a peer (repeatable)")->takeAll();
  app.addOption("--mode", o.mode, "fast or exact")->check(cli::isMember({"fast", "exact"}));
  cli::Option* server = app.addOption("--server-key", o.server_key, "the server's key");
  app.addOption("--key", o.key, "this client's key")->needs(server);
}

Result<Options> finish(Options options, Raw&) { return options; }

Result<Options> parse(const std::vector<std::string>& args, bool* help = nullptr) {
  return cli::parseToolOptions<Options, Raw>(args, help, makeApp, define, finish);
}

std::string errorOf(const std::vector<std::string>& args) {
  auto parsed = parse(args);
  REQUIRE_FALSE(parsed);
  CHECK(parsed.error().code == cli::CommandLineErrc::kBadOption);
  return parsed.error().message;
}

}  // namespace

TEST_CASE("Options parse into their variables", "[cli]") {
  auto parsed = parse({"--count", "7", "--scale=0.25", "--quiet", "--peer", "a", "--peer", "b",
                       "--mode", "exact", "--server-key", "s.key", "--key", "c.key_secret"});
  REQUIRE(parsed);
  CHECK(parsed->count == 7);
  CHECK(parsed->scale == 0.25);
  CHECK(parsed->quiet);
  CHECK(parsed->peers == std::vector<std::string>{"a", "b"});
  CHECK(parsed->mode == "exact");
  CHECK(parsed->key == "c.key_secret");

  auto defaults = parse({});
  REQUIRE(defaults);
  CHECK(defaults->count == 3);
  CHECK_FALSE(defaults->quiet);
  CHECK(defaults->peers.empty());
}

TEST_CASE("A bad command line is reported by the option at fault", "[cli]") {
  CHECK(errorOf({"--speed", "3"}) == "unknown option '--speed'");
  CHECK(errorOf({"--count"}) == "--count: missing value");
  CHECK_THAT(errorOf({"--count", "11"}),
             Catch::StartsWith("--count") && Catch::Contains("1 to 10"));
  CHECK_THAT(errorOf({"--count", "many"}), Catch::Contains("--count"));
  CHECK_THAT(errorOf({"--scale", "0.01"}), Catch::StartsWith("--scale"));
  CHECK_THAT(errorOf({"--mode", "slow"}), Catch::StartsWith("--mode") && Catch::Contains("slow"));
  CHECK_THAT(errorOf({"--key", "c.key_secret"}), Catch::Contains("--server-key"));
}

TEST_CASE("The help flag is answered before what options require of each other", "[cli]") {
  bool help = false;
  auto parsed = parse({"--key", "c.key_secret", "--help"}, &help);
  CHECK(parsed);
  CHECK(help);
  // A value its check refuses is still reported.
  CHECK_FALSE(parse({"--count", "99", "--help"}, &help));

  const std::string usage = cli::toolUsage<Options, Raw>(makeApp, define);
  CHECK_THAT(usage, Catch::Contains("A tool for the tests."));
  CHECK_THAT(usage, Catch::Contains("--count N"));  // the value's name
  CHECK_THAT(usage, Catch::Contains("INT in [1 - 10]"));
  CHECK_THAT(usage, Catch::Contains("FLOAT in [0.05 - 1]"));
  CHECK_THAT(usage, Catch::Contains("=3"));  // the default shown
  CHECK_THAT(usage, Catch::Contains("say less"));
}

TEST_CASE("A tool's main gets its exit code and the help on the right stream", "[cli]") {
  const auto run = [](std::vector<std::string> words, std::string* out, std::string* err) {
    cli::App app = makeApp();
    Options options;
    Raw raw;
    define(app, options, raw);
    std::vector<char*> argv;
    for (std::string& word : words) argv.push_back(word.data());
    std::ostringstream cout_text, cerr_text;
    auto* cout_was = std::cout.rdbuf(cout_text.rdbuf());
    auto* cerr_was = std::cerr.rdbuf(cerr_text.rdbuf());
    const std::optional<int> code =
        cli::parseMainArgs(app, static_cast<int>(argv.size()), argv.data());
    std::cout.rdbuf(cout_was);
    std::cerr.rdbuf(cerr_was);
    *out = cout_text.str();
    *err = cerr_text.str();
    return code;
  };
  std::string out, err;
  CHECK(run({"tool", "--count", "4"}, &out, &err) == std::nullopt);
  CHECK(run({"tool", "--help"}, &out, &err) == 0);
  CHECK_THAT(out, Catch::Contains("--count"));
  CHECK(err.empty());
  CHECK(run({"tool", "--count", "0"}, &out, &err) == 2);
  CHECK(out.empty());
  CHECK_THAT(err, Catch::StartsWith("tool: --count") && Catch::Contains("--scale"));
}

TEST_CASE("An app moved out of the function that built it keeps its options", "[cli]") {
  Options options;
  Raw raw;
  cli::App built = makeApp();
  define(built, options, raw);
  cli::App moved = std::move(built);
  REQUIRE_FALSE(moved.parse({"--count", "5", "--quiet"}, nullptr));
  CHECK(options.count == 5);
  CHECK(options.quiet);
  CHECK(moved.givenOptions() == std::set<std::string>{"count", "quiet"});
}

TEST_CASE("A config file's keys are the options, the command line wins", "[cli][config]") {
  TempDir dir;
  const std::string path = dir.write("tool.yaml",
                                     "count: 8\n"
                                     "quiet: true\n"
                                     "peer: [a, b]\n"
                                     "mode: exact\n");
  auto parsed = parse({"--config", path, "--count", "2"});
  REQUIRE(parsed);
  CHECK(parsed->count == 2);
  CHECK(parsed->quiet);
  CHECK(parsed->peers == std::vector<std::string>{"a", "b"});
  CHECK(parsed->mode == "exact");

  const std::string off = dir.write("off.yaml", "quiet: false\n");
  auto quiet_off = parse({"--config", off});
  REQUIRE(quiet_off);
  CHECK_FALSE(quiet_off->quiet);
}

TEST_CASE("A bad config file names the file and the key", "[cli][config]") {
  TempDir dir;
  const auto errorFor = [&](const std::string& yaml) {
    const std::string path = dir.write("tool.yaml", yaml);
    const std::string message = errorOf({"--config", path});
    CHECK_THAT(message, Catch::Contains(path));
    return message;
  };
  CHECK_THAT(errorFor("speed: 3\n"), Catch::Contains("speed: unknown key"));
  CHECK_THAT(errorFor("quiet: maybe\n"), Catch::Contains("quiet: must be true or false"));
  CHECK_THAT(errorFor("quiet: [true]\n"), Catch::Contains("quiet: must be true or false"));
  CHECK_THAT(errorFor("--count: 3\n"), Catch::Contains("unknown key"));
  CHECK_THAT(errorFor("count: [1, 2]\n"), Catch::Contains("count: takes one value, not a list"));
  CHECK_THAT(errorFor("peer: {a: 1}\n"), Catch::Contains("peer: must be a value"));
  CHECK_THAT(errorFor("count: 30\n"), Catch::Contains("count: ") && Catch::Contains("1 to 10"));
  CHECK_THAT(errorFor("- count\n"), Catch::Contains("must be a map"));
  CHECK_THAT(errorFor("config: other.yaml\n"), Catch::Contains("config: unknown key"));
  CHECK_THAT(errorFor("count: [\n"), Catch::Contains("--config"));
}
