// PLC trigger to results valid, beside LOCATE over the robot port, in the
// same run: the real picksight-video-server (synthetic camera, trigger
// mode) and picksight-vision with its Modbus port; libmodbus's client as
// the PLC, polling the status register every 0.2 ms (far faster than any
// PLC cycle, so the figure is the vision app's, plus at most 0.2 ms). The two
// kinds of request alternate, so machine noise hits both alike.
#include <modbus/modbus.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <thread>
#include <vector>

#include "bench_cell.hpp"
#include "locate_args.hpp"
#include "opencv_baseline.hpp"
#include "picksight/plc/register_map.hpp"

namespace {
using namespace std::chrono_literals;
using namespace picksight;
using namespace picksight::tool_support;
using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

uint16_t status(modbus_t* ctx) {
  uint16_t s = 0;
  return modbus_read_registers(ctx, plc::reg::kStatus, 1, &s) == 1 ? s : 0xFFFF;
}

bool write(modbus_t* ctx, uint16_t address, uint16_t value) {
  return modbus_write_register(ctx, address, value) == 1;
}

// One handshake: trigger, poll until results valid (or error), then drop
// the trigger and acknowledge. The time runs from the trigger's write to
// the status read that shows results valid. Negative: failed.
double timedTrigger(modbus_t* ctx) {
  const auto start = Clock::now();
  if (!write(ctx, plc::reg::kControl, plc::kControlTrigger)) return -1;
  uint16_t s = 0;
  while (((s = status(ctx)) & (plc::kStatusResultsValid | plc::kStatusError)) == 0) {
    if (s == 0xFFFF || Clock::now() - start > 10s) return -1;
    // A short pause: a poll loop back to back would take a core from the
    // vision app on a small machine; 0.2 ms is far below any PLC cycle.
    std::this_thread::sleep_for(200us);
  }
  const double ms = msSince(start);
  if ((s & plc::kStatusError) != 0) return -1;
  if (!write(ctx, plc::reg::kControl, plc::kControlResultsAck) ||
      !write(ctx, plc::reg::kControl, 0))
    return -1;
  return ms;
}
}  // namespace

int main(int argc, char** argv) {
  bench::LocateArgs defaults;
  defaults.requests = 200;
  defaults.width = 1280;
  defaults.height = 960;
  defaults.parts = 8;
  const bench::LocateArgs args = bench::parseLocateArgs(argc, argv, defaults);
  auto server = bench::startVideoServer(bench::syntheticCamera(args));
  if (!server) {
    std::fprintf(stderr, "plc_bench: video server did not start\n");
    return 1;
  }
  const std::string data_dir = bench::makeDataDir();
  Subprocess vision(std::vector<std::string>{
      bench::binDir() + "/picksight-vision", "--frames", server->frames, "--control",
      server->control, "--robot-port", "0", "--bind", "127.0.0.1", "--data-dir", data_dir,
      "--modbus-port", "0", "--modbus-bind", "127.0.0.1"});
  const auto robot_port = vision.waitForLine("robot ", 10s);
  const auto modbus_port = vision.waitForLine("modbus ", 10s);
  if (!robot_port || !modbus_port || !vision.waitForLine("ready", 10s)) {
    std::fprintf(stderr, "plc_bench: vision app did not start\n");
    return 1;
  }
  auto robot = LineClient::connect("127.0.0.1", static_cast<uint16_t>(std::stoi(*robot_port)), 5s);
  modbus_t* plc = modbus_new_tcp("127.0.0.1", std::stoi(*modbus_port));
  if (!robot || !plc || modbus_connect(plc) != 0) {
    std::fprintf(stderr, "plc_bench: cannot connect\n");
    return 1;
  }
  modbus_set_slave(plc, 1);
  modbus_set_response_timeout(plc, 5, 0);
  // No model: every region is a part, on both ports.
  write(plc, plc::reg::kPartType, 0);

  std::vector<double> trigger_ms;
  std::vector<double> locate_ms;
  int failures = 0;
  for (int i = 0; i < 10; ++i) {  // warm-up: first frames, buffers, caches
    (void)timedTrigger(plc);
    (void)robot->request("LOCATE 0", 10s);
  }
  for (int i = 0; i < args.requests; ++i) {
    const double t = timedTrigger(plc);
    if (t < 0) {
      ++failures;
    } else {
      trigger_ms.push_back(t);
    }
    const auto start = Clock::now();
    const auto reply = robot->request("LOCATE 0", 10s);
    if (reply && reply->rfind("OK ", 0) == 0) {
      locate_ms.push_back(msSince(start));
    } else {
      ++failures;
    }
  }
  std::printf("PLC bench: %dx%d, %d parts, %d rounds (trigger then LOCATE), %d failures\n",
              args.width, args.height, args.parts, args.requests, failures);
  std::printf("  Modbus trigger -> results valid  median %.2f ms  p99 %.2f ms  (n=%zu)\n",
              bench::nearestRank(trigger_ms, 50), bench::nearestRank(trigger_ms, 99),
              trigger_ms.size());
  std::printf("  robot LOCATE round trip          median %.2f ms  p99 %.2f ms  (n=%zu)\n",
              bench::nearestRank(locate_ms, 50), bench::nearestRank(locate_ms, 99),
              locate_ms.size());
  modbus_close(plc);
  modbus_free(plc);
  vision.terminate();
  std::error_code ignored;
  std::filesystem::remove_all(data_dir, ignored);
  return failures == 0 ? 0 : 1;
}
