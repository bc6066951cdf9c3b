// picksight-robot's interactive mode: a prompt with line editing and a
// history kept across runs (libedit), like a database shell.
#pragma once

#include <ostream>
#include <string>

#include "robot_cli.hpp"

namespace picksight::robot {

// Where the history is kept: $HOME/.picksight_robot_history (empty when
// HOME is unset: then nothing is kept).
std::string historyPath();

// Prompts on the terminal until end of input (Ctrl-D) or `quit`/`exit`,
// sending each line and printing its reply; a lost connection is reported
// and the next request connects again. Returns kExitOk, or kExitFailure
// when the very first connection could not be made. Reads the terminal, so
// one per process.
int runInteractive(RobotSession& session, std::ostream& out, std::ostream& err);

}  // namespace picksight::robot
