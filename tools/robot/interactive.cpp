// Interactive mode over libedit's readline interface (BSD licence, Debian's
// libedit-dev).
#include "interactive.hpp"

#include <editline/readline.h>

#include <cctype>
#include <cstdlib>
#include <memory>
#include <sstream>

#include "picksight/common/text.hpp"

namespace picksight::robot {
namespace {

// Enough for every request of a long set-up session, small enough to load
// at once.
constexpr int kHistoryEntries = 1000;

bool isQuit(const std::string& line) {
  const auto words = splitFields(line, " \t");
  if (words.size() != 1) return false;
  std::string w(words[0]);
  for (auto& c : w) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return w == "quit" || w == "exit";
}

}  // namespace

std::string historyPath() {
  const char* home = std::getenv("HOME");
  if (!home || !*home) return {};
  return std::string(home) + "/.picksight_robot_history";
}

int runInteractive(RobotSession& session, std::ostream& out, std::ostream& err) {
  // Connect at once: a wrong host or port is better said before any typing.
  std::ostringstream pong;
  if (session.send("PING", pong, err) == kExitFailure) return kExitFailure;
  out << "connected to " << session.peer() << "; HELP lists the requests, Ctrl-D or quit ends\n";

  const std::string history = historyPath();
  using_history();
  stifle_history(kHistoryEntries);
  if (!history.empty()) read_history(history.c_str());
  const std::string prompt = session.peer() + "> ";
  for (;;) {
    std::unique_ptr<char, decltype(&std::free)> raw(readline(prompt.c_str()), &std::free);
    if (!raw) {
      out << "\n";
      break;
    }
    std::string line(raw.get());
    if (isComment(line)) continue;
    if (isQuit(line)) break;
    add_history(line.c_str());
    // A failure was printed; the next request tries a new connection.
    session.send(line, out, err);
  }
  if (!history.empty()) write_history(history.c_str());
  return kExitOk;
}

}  // namespace picksight::robot
