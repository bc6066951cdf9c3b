// picksight-robot entry point: one-shot requests from the arguments, a
// script from stdin, or an interactive prompt on a terminal.
#include <unistd.h>

#include <iostream>
#include <string>
#include <vector>

#include "interactive.hpp"
#include "robot_cli.hpp"

using namespace picksight::robot;

int main(int argc, char** argv) {
  auto options = parseCommandLine(std::vector<std::string>(argv + 1, argv + argc));
  if (!options) {
    std::cerr << kProgram << ": " << options.error().message << " (see --help)\n";
    return kExitFailure;
  }
  if (!options->help_text.empty()) {
    std::cout << options->help_text;
    return kExitOk;
  }
  RobotSession session(*options);
  if (!options->commands.empty())
    return runCommands(session, options->commands, std::cout, std::cerr);
  if (::isatty(STDIN_FILENO)) return runInteractive(session, std::cout, std::cerr);
  return runScript(session, std::cin, std::cout, std::cerr);
}
