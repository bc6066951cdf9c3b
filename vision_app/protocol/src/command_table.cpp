// Robot protocol command table and request parsing.
#include "picksight/protocol/command_table.hpp"

#include "picksight/common/log.hpp"
#include "picksight/common/text.hpp"
#include "picksight/protocol/robot_errors.hpp"

namespace picksight::protocol {

const char* errorName(ProtocolErrc e) {
  switch (e) {
    case ProtocolErrc::kUnknownCommand:
      return "unknown command";
    case ProtocolErrc::kBadArguments:
      return "bad arguments";
    case ProtocolErrc::kRequestTooLong:
      return "request too long";
    case ProtocolErrc::kTooManyConnections:
      return "too many connections";
    case ProtocolErrc::kEmptyRequest:
      return "empty request";
    case ProtocolErrc::kInternalError:
      return "internal error";
    case ProtocolErrc::kNotAllowed:
      return "not allowed";
    case ProtocolErrc::kIdle:
      return "idle";
    case ProtocolErrc::kReadOnly:
      return "read-only port";
  }
  return "unknown";
}

std::string errorReply(const Error& error) {
  return "ERROR " + std::to_string(robotErrorCode(error.code)) + " " + error.message;
}

std::optional<int> parseType(std::string_view text) {
  const auto type = parseInt(text);
  if (!type || *type < 0 || *type > 9999) return std::nullopt;
  return static_cast<int>(*type);
}

std::optional<std::vector<double>> parseNumbers(const std::vector<std::string>& args,
                                                size_t first) {
  std::vector<double> out;
  for (size_t i = first; i < args.size(); ++i) {
    const auto v = parseDouble(args[i]);
    if (!v) return std::nullopt;
    out.push_back(*v);
  }
  return out;
}

std::string printable(std::string_view text, size_t limit) {
  std::string out;
  for (char c : text.substr(0, limit)) {
    out +=
        (static_cast<unsigned char>(c) >= 0x20 && static_cast<unsigned char>(c) < 0x7f) ? c : '?';
  }
  if (text.size() > limit) out += "...";
  return out;
}

std::optional<Request> parseRequest(std::string_view line) {
  const auto fields = splitFields(line, " \t,");
  if (fields.empty()) return std::nullopt;
  Request r;
  r.command = toUpper(fields[0]);
  r.line = std::string(line);
  for (size_t i = 1; i < fields.size(); ++i) r.args.emplace_back(fields[i]);
  return r;
}

bool changesUnlessList(const Request& r) {
  return r.args.size() < 2 || toUpper(r.args[1]) != "LIST";
}

void CommandTable::add(const std::string& word, const std::string& usage, Handler handler,
                       ChangesCell changes, Publishes publishes) {
  commands_[toUpper(word)] = Entry{usage, std::move(handler), std::move(changes), publishes};
}

std::string CommandTable::dispatch(std::string_view line, bool read_only, Session* session) const {
  if (session) {
    session->command.clear();
    session->publishes = Publishes::kNothing;
    session->record = nullptr;
    session->frame = nullptr;
    session->changed = false;
  }
  auto request = parseRequest(line);
  if (!request) return errorReply(ProtocolErrc::kEmptyRequest, "empty request");
  const auto it = commands_.find(request->command);
  if (it == commands_.end()) {
    return errorReply(ProtocolErrc::kUnknownCommand,
                      "unknown command '" + printable(request->command) + "' (try HELP)");
  }
  if (session) {
    session->command = request->command;
    session->publishes = it->second.publishes;
  }
  if (read_only && it->second.changes(*request)) {
    return errorReply(ProtocolErrc::kReadOnly,
                      request->command + " " +
                          (request->args.empty() ? "" : "with these arguments ") +
                          "changes the cell: refused on this read-only port (use the set-up port)");
  }
  Session local;
  if (!session) local.received = std::chrono::steady_clock::now();
  request->session = session ? session : &local;
  std::string reply = it->second.handler(*request);
  // Every change made at a robot's, a PLC's or the set-up port's request,
  // in the log (journald under systemd), with who asked and what came back:
  // the web keeps its own trail of the changes made through it and learns
  // of these from the results stream (Session::changed). Only changes
  // made (an OK): a refused one changed nothing, and a peer sending garbage
  // in a loop (the robot fuzzer logged 290,000 lines in 20 s) must not fill
  // the journal. Bounded: the line as the request limit allows it, the
  // reply's first 120 characters.
  if (it->second.changes(*request) && reply.rfind("OK", 0) == 0) {
    request->session->changed = true;
    logInfo("audit: ", session && !session->client.empty() ? session->client : "local", " '",
            printable(line, 200), "' -> ", printable(reply, 120));
  }
  if (!session && local.after_reply) local.after_reply(reply);
  return reply;
}

std::string CommandTable::help() const {
  std::string out = "OK";
  bool first = true;
  for (const auto& [word, entry] : commands_) {
    out += first ? " " : " | ";
    out += entry.usage;
    first = false;
  }
  return out;
}

}  // namespace picksight::protocol
