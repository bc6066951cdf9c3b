// JOB: save, load, list, delete, export and import the cell's jobs.
#include "picksight/protocol/job_commands.hpp"

#include <string>

#include "picksight/common/text.hpp"

namespace picksight::protocol {
namespace {

constexpr const char* kUsage =
    "JOB [SAVE <name> | LOAD <name> | LIST | DELETE <name> | EXPORT <name> [<offset>] | "
    "IMPORT <name> <offset> <total> <base64>]";

std::string usage() {
  return errorReply(ProtocolErrc::kBadArguments, std::string("usage: ") + kUsage);
}

std::string summaryFields(const jobs::JobSummary& s) {
  return s.name + " " + std::to_string(s.models) + " " + (s.calibrated ? "1" : "0") + " " +
         (s.camera ? "1" : "0");
}

// An offset or size argument: a whole number of bytes.
std::optional<size_t> bytesArgument(const std::string& text) {
  if (text.empty() || text.size() > 12 || text.find_first_not_of("0123456789") != std::string::npos)
    return std::nullopt;
  return static_cast<size_t>(std::stoull(text));
}

std::string importPiece(jobs::JobSwitch& jobs, const Request& r) {
  if (r.args.size() != 5) return usage();
  const auto offset = bytesArgument(r.args[2]);
  const auto total = bytesArgument(r.args[3]);
  if (!offset || !total)
    return errorReply(ProtocolErrc::kBadArguments, "offset and total are byte counts");
  auto bytes = jobs::base64Decode(r.args[4]);
  if (!bytes) return errorReply(ProtocolErrc::kBadArguments, "the piece is not base64");
  auto imported = jobs.importPiece(r.args[1], *offset, *total, *bytes);
  if (!imported) return errorReply(imported.error());
  // Not OK until the last piece: only the import itself changes the cell
  // (and is logged and published as a change).
  if (!*imported) return "MORE " + std::to_string(*offset + bytes->size()) + " " + r.args[3];
  return "OK " + summaryFields(**imported) + " " + std::to_string((*imported)->bytes);
}

std::string job(jobs::JobSwitch& jobs, const Request& r) {
  if (r.args.empty()) {
    const auto current = jobs.current();
    return "OK " + current.value_or("none");
  }
  const std::string sub = toUpper(r.args[0]);
  if (sub == "LIST") {
    if (r.args.size() != 1) return usage();
    auto list = jobs.list();
    if (!list) return errorReply(list.error());
    std::string reply = "OK " + std::to_string(list->size());
    for (const auto& entry : *list) reply += " " + entry.name;
    return reply;
  }
  if (sub == "IMPORT") return importPiece(jobs, r);
  if (sub == "EXPORT") {
    if (r.args.size() != 2 && r.args.size() != 3) return usage();
    const auto offset = r.args.size() == 3 ? bytesArgument(r.args[2]) : std::optional<size_t>(0);
    if (!offset) return errorReply(ProtocolErrc::kBadArguments, "the offset is a byte count");
    auto piece = jobs.exportPiece(r.args[1], *offset, kJobExportPiece);
    if (!piece) return errorReply(piece.error());
    return "OK " + std::to_string(piece->second) + " " + std::to_string(*offset) + " " +
           jobs::base64Encode(piece->first);
  }
  if (r.args.size() != 2) return usage();
  const std::string& name = r.args[1];
  if (sub == "SAVE") {
    auto saved = jobs.save(name);
    if (!saved) return errorReply(saved.error());
    std::string reply = "OK " + summaryFields(*saved) + " " + std::to_string(saved->bytes);
    if (!saved->note.empty()) reply += " ; note: " + printable(saved->note, 200);
    return reply;
  }
  if (sub == "LOAD") {
    auto loaded = jobs.load(name);
    if (!loaded) return errorReply(loaded.error());
    return "OK " + summaryFields(*loaded);
  }
  if (sub == "DELETE") {
    if (auto removed = jobs.remove(name); !removed) return errorReply(removed.error());
    return "OK " + name;
  }
  return usage();
}

// SAVE, LOAD, DELETE and IMPORT change the cell (or its stored jobs).
bool jobChanges(const Request& r) {
  if (r.args.empty()) return false;
  const std::string sub = toUpper(r.args[0]);
  return sub == "SAVE" || sub == "LOAD" || sub == "DELETE" || sub == "IMPORT";
}

}  // namespace

void addJobCommands(CommandTable& table, jobs::JobSwitch& jobs) {
  table.add(
      "JOB", kUsage, [&jobs](const Request& r) { return job(jobs, r); }, jobChanges);
}

}  // namespace picksight::protocol
