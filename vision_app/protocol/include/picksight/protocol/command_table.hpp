// The robot protocol's command table: each feature of the vision app
// registers its command words with their usage and handler, so commands live
// beside the code they drive and HELP lists them all.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "picksight/common/result.hpp"
#include "picksight/protocol/session.hpp"

namespace picksight::protocol {

// Failures of the protocol itself, shared by every command.
enum class ProtocolErrc {
  kUnknownCommand = 1,
  kBadArguments,
  kRequestTooLong,      // sent by RobotServer
  kTooManyConnections,  // sent by RobotServer
  kEmptyRequest,
  kInternalError,
  kNotAllowed,  // sent by RobotServer: the peer is not in the allow-list
  kIdle,        // sent by RobotServer: no request for the idle timeout
  kReadOnly,    // a request that changes the cell, on a read-only port
};
const char* errorName(ProtocolErrc e);
PICKSIGHT_ERROR_DOMAIN(ProtocolErrc, "robot protocol")

// A parsed request: the command word upper-cased and its arguments, split
// on spaces, tabs or commas.
struct Request {
  std::string command;
  std::vector<std::string> args;
  std::string line;  // as received
  // The connection's session; dispatch() always sets it (a fresh one when
  // its caller has none, whose after_reply runs before dispatch returns).
  Session* session = nullptr;
};

// Nullopt for an empty or blank line.
std::optional<Request> parseRequest(std::string_view line);

// "ERROR <code> <text>", the code from the protocol's one table
// (robot_errors.hpp).
std::string errorReply(const Error& error);
template <typename E>
std::string errorReply(E code, const std::string& text) {
  return errorReply(makeError(code, text));
}
// A part type argument: an integer in [0, 9999].
std::optional<int> parseType(std::string_view text);
// Every argument from `first` on as a finite number; nullopt if one is not.
std::optional<std::vector<double>> parseNumbers(const std::vector<std::string>& args,
                                                size_t first = 0);
// Up to `limit` characters of client text, safe to echo in a reply line.
std::string printable(std::string_view text, size_t limit = 40);

// Whether a request changes the cell (a model, a calibration, a camera
// setting), and is therefore refused on a read-only port. A command that
// reads with some arguments and writes with others decides per request.
using ChangesCell = std::function<bool(const Request&)>;
inline bool alwaysChanges(const Request&) { return true; }
inline bool neverChanges(const Request&) { return false; }
// True unless the request has no argument (EXPOSURE, ROI: read the setting).
inline bool changesWithArguments(const Request& r) { return !r.args.empty(); }
// True unless the sub-command (second argument) is LIST (GRASP, GRIPPER).
bool changesUnlessList(const Request& r);

class CommandTable {
 public:
  // Returns the whole reply line (without line end).
  using Handler = std::function<std::string(const Request&)>;

  // Registers (or replaces) a command word, upper case. A command changes
  // the cell unless it says otherwise, so that a new command is refused on
  // a read-only port until someone decides it only reads. `publishes`:
  // what its requests publish (see Session).
  void add(const std::string& word, const std::string& usage, Handler handler,
           ChangesCell changes = alwaysChanges, Publishes publishes = Publishes::kNothing);
  // Parses and runs one request line. On a read-only port a request that
  // changes the cell gets ProtocolErrc::kReadOnly and does nothing; one that
  // runs is logged as `audit: <client> '<line>' -> <reply>`. The
  // session's command and publishes are its entry's, refused or not. With
  // `session` (a connection's), its after_reply is left for the caller to
  // run once the reply is sent; without, it runs before this returns.
  // Thread-safe once set up.
  std::string dispatch(std::string_view line, bool read_only = false,
                       Session* session = nullptr) const;
  // "OK" and every usage, separated by " | ".
  std::string help() const;

 private:
  struct Entry {
    std::string usage;
    Handler handler;
    ChangesCell changes;
    Publishes publishes = Publishes::kNothing;
  };
  std::map<std::string, Entry> commands_;
};

}  // namespace picksight::protocol

PICKSIGHT_ERROR_ENUM(picksight::protocol::ProtocolErrc)
