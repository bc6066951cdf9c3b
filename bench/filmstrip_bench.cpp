// What the filmstrip costs LOCATE: the robot's round trip (fresh frame
// included, 1920x1080 with 20 parts by default) with recording off, on as
// by default, and on with every success written, in alternating rounds
// against the same video server in the same run, so that all see the same
// machine load. Prints median and p99 of each, the cost at the median, and
// per round what the filmstrip wrote, sampled out and dropped.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "bench_cell.hpp"
#include "locate_args.hpp"
#include "opencv_baseline.hpp"
#include "picksight/common/text.hpp"

namespace {
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// One round: a vision app with `options` on `server`, `requests` LOCATEs
// timed after a warm-up; the round trips appended to `ms`. The filmstrip's
// STATUS line at the end (empty without one). False when the app failed.
bool round(const picksight::bench::VideoServerRun& server, const std::vector<std::string>& options,
           int requests, std::vector<double>& ms, std::string& status) {
  const std::string data_dir = picksight::bench::makeDataDir();
  auto vision = picksight::bench::startVision(server, data_dir, options);
  if (!vision) return false;
  for (int i = 0; i < 5; ++i) (void)vision->robot.request("LOCATE 1", 10s);
  for (int i = 0; i < requests; ++i) {
    const auto t0 = Clock::now();
    auto reply = vision->robot.request("LOCATE 1", 10s);
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    if (!reply || reply->rfind("OK", 0) != 0) {
      std::cerr << "bench: LOCATE 1 -> " << (reply ? *reply : reply.error().message) << "\n";
      return false;
    }
  }
  auto figures = vision->robot.request("FILMSTRIP STATUS", 10s);
  status = figures && figures->rfind("OK", 0) == 0 ? figures->substr(3) : "";
  vision->process->terminate();
  std::error_code ignored;
  std::filesystem::remove_all(data_dir, ignored);
  return true;
}
}  // namespace

int main(int argc, char** argv) {
  int rounds = 4;
  const auto args = picksight::bench::parseLocateArgs(
      argc, argv, {400, 1920, 1080, 20}, [&](picksight::cli::App& app) {
        app.addOption("--rounds", rounds, "alternating rounds of each (requests split among them)")
            ->check(picksight::cli::positiveNumber())
            ->showDefault();
      });
  auto server = picksight::bench::startVideoServer(picksight::bench::syntheticCamera(args));
  if (!server) return 1;
  const int per_round = std::max(1, args.requests / rounds);
  // Off; on as the app starts by default (a success a second at most);
  // on with every success written (--filmstrip-success-ms 0).
  struct Mode {
    const char* name;
    std::vector<std::string> options;
    std::vector<double> ms;
    std::vector<double> medians;  // per round: the load moves between rounds
    std::vector<std::string> statuses;
  };
  std::vector<Mode> modes{
      {"filmstrip off", {"--filmstrip-dir", "none"}, {}, {}, {}},
      {"filmstrip on (default)", {}, {}, {}, {}},
      {"filmstrip on, every success", {"--filmstrip-success-ms", "0"}, {}, {}, {}}};
  for (int r = 0; r < rounds; ++r) {
    // Each round starts with another mode: none always follows the same.
    for (size_t k = 0; k < modes.size(); ++k) {
      Mode& m = modes[(k + static_cast<size_t>(r)) % modes.size()];
      std::vector<double> ms;
      std::string status;
      if (!round(*server, m.options, per_round, ms, status)) return 1;
      m.medians.push_back(picksight::bench::nearestRank(ms, 50));
      m.statuses.push_back(status);
      m.ms.insert(m.ms.end(), ms.begin(), ms.end());
    }
  }
  server->process->terminate();
  using picksight::bench::nearestRank;
  std::printf("LOCATE round trip, %dx%d, %d parts, %d rounds of %d requests each way (ms):\n",
              args.width, args.height, args.parts, rounds, per_round);
  std::printf("  %-30s %8s %8s %10s\n", "", "median", "p99", "vs off");
  const double off = nearestRank(modes[0].ms, 50);
  for (const auto& m : modes) {
    std::printf("  %-30s %8.2f %8.2f %+9.1f%%\n", m.name, nearestRank(m.ms, 50),
                nearestRank(m.ms, 99), 100.0 * (nearestRank(m.ms, 50) / off - 1));
  }
  for (int r = 0; r < rounds; ++r) {
    std::printf("  round %d medians: off %.2f, default %.2f, every %.2f\n", r + 1,
                modes[0].medians[static_cast<size_t>(r)], modes[1].medians[static_cast<size_t>(r)],
                modes[2].medians[static_cast<size_t>(r)]);
    for (size_t k = 1; k < modes.size(); ++k)
      std::printf("    %s: %s\n", modes[k].name, modes[k].statuses[static_cast<size_t>(r)].c_str());
  }
  return 0;
}
