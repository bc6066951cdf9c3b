// The robot protocol (docs/PROTOCOL.md): the core commands (PING, VERSION,
// HELP, FRAME) over a CommandTable that the other features extend (LOCATE
// and the cell: cell_commands.hpp; VisionCell wires them all).
#pragma once

#include <string>
#include <string_view>

#include "picksight/cell/vision_service.hpp"
#include "picksight/protocol/command_table.hpp"

namespace picksight::protocol {

class RobotProtocol {
 public:
  explicit RobotProtocol(cell::VisionService& vision);

  // One request line in, one reply line out; on a read-only port requests
  // that change the cell are refused. Thread-safe.
  // With a connection's `session`, its after_reply is the caller's to run.
  std::string handle(std::string_view line, bool read_only = false,
                     Session* session = nullptr) const {
    return table_.dispatch(line, read_only, session);
  }
  // For features that add commands; only before serving starts.
  CommandTable& table() { return table_; }

 private:
  std::string frame(const Request& request);

  cell::VisionService& vision_;
  CommandTable table_;
};

}  // namespace picksight::protocol
