// One robot connection's state across its requests: who it is, when the
// current request arrived and what it publishes, the last LOCATE (for
// WHY), and what to do once the current reply has been written (publish
// its result).
//
// Threading: owned by the connection's thread; requests on one connection
// are served one after the other, so nothing here needs a lock.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "picksight/results/request_record.hpp"

namespace picksight::protocol {

// What a request publishes on the results stream once its reply is sent;
// its command's table entry says (CommandTable::add), VisionCell publishes.
enum class Publishes {
  kNothing,
  kFrame,   // the fresh frame it worked on, with its regions (LEARN, BLOBS, STORE, CALCAM)
  kRecord,  // the record its handler leaves in Session::record (LOCATE)
};

struct Session {
  std::string client;  // "robot 10.0.0.5:41234", "setup 127.0.0.1:5012"; empty: local
  std::chrono::steady_clock::time_point received{};  // of the current request
  // Set by a handler; RobotServer runs it (and clears it) once the reply
  // line has been sent, so that nothing it does delays the robot.
  std::function<void(const std::string& reply)> after_reply;
  // The last LOCATE on this connection (null before any), for WHY.
  std::shared_ptr<const results::RequestRecord> last_locate;
  // Of the current request, set by CommandTable::dispatch from its entry
  // (empty, kNothing for a line no entry took): the command word and what
  // it publishes; and the record its handler leaves (Publishes::kRecord).
  std::string command;
  Publishes publishes = Publishes::kNothing;
  // Whether the current request changed the cell (answered OK): published
  // for the web's audit trail.
  bool changed = false;
  std::shared_ptr<results::RequestRecord> record;
  // The frame the current LOCATE worked on (null for others), for the
  // filmstrip; VisionCell takes it, so that no session keeps a frame.
  std::shared_ptr<const Frame> frame;
  // The filmstrip entry of this connection's last LOCATE (0: none), which
  // its WHY explains.
  uint64_t last_locate_entry = 0;
};

}  // namespace picksight::protocol
