// picksight-vision's offline subcommands: learn, locate and blobs on image
// files, with the same model library and reply lines as the robot protocol;
// lens, the lens model from chessboard views into the calibration file.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

namespace picksight::app {

// True when args[0] names a subcommand (learn, locate, blobs, lens).
bool isOfflineCommand(const std::vector<std::string>& args);

// Runs one subcommand (args without the program name); returns the exit
// code: 0 done, 1 failed (an ERROR line was printed), 2 bad usage.
int runOfflineCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

std::string offlineUsage();

}  // namespace picksight::app
