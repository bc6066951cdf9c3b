// Robot protocol commands over the filmstrip (docs/PROTOCOL.md): FILMSTRIP
// lists, shows, sends and exports recent requests' frames; REPLAY runs a
// stored frame through the models in use now and answers as LOCATE would.
#pragma once

#include <string>

#include "picksight/cell/cell_locate.hpp"
#include "picksight/filmstrip/filmstrip.hpp"
#include "picksight/protocol/command_table.hpp"

namespace picksight::protocol {

// Most entries one FILMSTRIP lists.
constexpr size_t kMaxListed = 100;
// The largest side FILMSTRIP IMAGE sends (the frame shrunk to fit).
constexpr int kMaxImageSide = 2048;

// Registers FILMSTRIP and REPLAY. `filmstrip` is read at each request
// (null: --filmstrip-dir none, every request is ERROR 57); `cell` and the
// pointer outlive `table`.
void addFilmstripCommands(CommandTable& table, cell::CellContext& cell,
                          const filmstrip::Filmstrip* const& filmstrip);

// Where FILMSTRIP EXPORT <name> writes: <filmstrip dir>/exports/<name>.
std::string exportPath(const filmstrip::Filmstrip& filmstrip, const std::string& name);

}  // namespace picksight::protocol
