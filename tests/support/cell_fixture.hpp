// A cell for end-to-end tests: the real picksight-video-server and
// picksight-vision processes started on free ports, and helpers to talk to
// them as a robot, a viewer or an integrator at a shell would.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <zmq.hpp>

#include "picksight/tool_support/line_client.hpp"
#include "picksight/tool_support/subprocess.hpp"
#include "picksight/transport/frame_message.hpp"

namespace picksight::e2e {

std::string binPath(const std::string& name);

struct VideoServerProcess {
  // Starts the server with `args` plus free-port endpoints; REQUIREs that it
  // printed its endpoints. With a `log_file` its stderr (the log) goes there.
  explicit VideoServerProcess(std::vector<std::string> args, const std::string& log_file = "");
  std::unique_ptr<tool_support::Subprocess> process;
  std::string frames;
  std::string control;
};

struct VisionProcess {
  // With an empty `data_dir` a fresh one, removed at the end; a given one
  // is kept (restart tests). `extra_args` are added to the command line; with
  // --setup-port, setup_port is the port it printed.
  VisionProcess(const VideoServerProcess& server, const std::string& camera = "cam0",
                const std::string& data_dir = "", const std::vector<std::string>& extra_args = {});
  ~VisionProcess();
  std::unique_ptr<tool_support::Subprocess> process;
  uint16_t robot_port = 0;
  uint16_t setup_port = 0;
  std::string results_endpoint;  // empty with --results-bind none
  std::string data_dir;
  bool own_data_dir = true;
  tool_support::LineClient connect() const;
};

// A cell whose camera is one photograph of tests/data/scenes (a file
// camera in trigger mode), and a robot's connection to its vision app.
struct PhotographCell {
  // `scene_file`: a file of tests/data/scenes, or an absolute path.
  explicit PhotographCell(const std::string& scene_file);
  // The reply to `line`; REQUIREs one within 20 s.
  std::string ask(const std::string& line);
  VideoServerProcess server;
  VisionProcess vision;
  tool_support::LineClient robot;
};

struct CommandResult {
  int exit_code = -1;
  std::string out;
};
// Runs a command line tool to completion, capturing stdout.
CommandResult run(const std::vector<std::string>& argv);

// Receives frames until one satisfies `accept` or `tries` frames went by.
std::optional<Frame> receiveUntil(transport::FrameSubscriber& subscriber,
                                  const std::function<bool(const Frame&)>& accept, int tries = 100);

// Sends software triggers to `camera` until `subscriber` has a frame (for a
// server in trigger mode): the subscription has then reached the server and
// nothing published later is lost to it. REQUIREs it within 10 s. Returns
// that frame's sequence number.
uint64_t waitForSubscription(const VideoServerProcess& server,
                             transport::FrameSubscriber& subscriber,
                             const std::string& camera = "cam0");

// The numbers of a reply "OK a b ..."; REQUIREs "OK" and `expected` numbers.
std::vector<double> replyNumbers(const std::string& reply, size_t expected);

// The reply "OK n x y rz ..." as (x, y, rz) triples; REQUIREs the format.
struct Pose {
  double x, y, rz;
};
std::vector<Pose> parseLocateReply(const std::string& reply);
// The same poses back in image axes (y down, angles clockwise on screen),
// angles in [0, 360): LOCATE replies in the vision frame (y up) before any
// calibration.
std::vector<Pose> imagePoses(const std::string& reply);

}  // namespace picksight::e2e
