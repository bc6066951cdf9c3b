// The roles of the web HMI's requests (access_policy.hpp).
#include "picksight/web/access_policy.hpp"

#include <algorithm>
#include <cctype>
#include <set>
#include <vector>

namespace picksight::web {
namespace {

std::vector<std::string> words(std::string_view line) {
  std::vector<std::string> out;
  std::string word;
  for (char c : line) {
    // The robot protocol splits on spaces, tabs and commas.
    if (c == ' ' || c == '\t' || c == ',') {
      if (!word.empty()) out.push_back(word);
      word.clear();
    } else {
      word += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    }
  }
  if (!word.empty()) out.push_back(word);
  return out;
}

}  // namespace

Role roleForCommand(std::string_view line) {
  static const std::set<std::string> reads = {"LOCATE",  "WHY",       "STATUS", "PING",
                                              "VERSION", "HELP",      "MODELS", "BLOBS",
                                              "LIST",    "RESIDUALS", "FRAME"};
  const auto w = words(line);
  if (w.empty()) return Role::kOperator;  // refused by the app anyway
  const std::string& command = w[0];
  if (reads.count(command) > 0) return Role::kOperator;
  // The filmstrip: replays and reads change nothing; an export writes a
  // folder on the vision app's host.
  if (command == "REPLAY") return Role::kOperator;
  if (command == "FILMSTRIP" && (w.size() < 2 || w[1] != "EXPORT")) return Role::kOperator;
  // Reads with these arguments, changes with more.
  if ((command == "EXPOSURE" || command == "ROI" || command == "CAMMODE" || command == "VISION") &&
      w.size() == 1)
    return Role::kOperator;
  if (command == "TOLERANCE" && w.size() <= 2) return Role::kOperator;
  if ((command == "GRASP" || command == "GRIPPER") && w.size() == 3 && w[2] == "LIST")
    return Role::kOperator;
  // Which job is in force, the list, a job's file: reads.
  if (command == "JOB" && (w.size() == 1 || w[1] == "LIST" || w[1] == "EXPORT"))
    return Role::kOperator;
  return Role::kEngineer;
}

bool isJobImportPiece(std::string_view line) {
  const auto w = words(line.substr(0, 16));
  return w.size() >= 2 && w[0] == "JOB" && w[1] == "IMPORT";
}

bool changesCell(std::string_view line) {
  if (roleForCommand(line) != Role::kEngineer) return false;
  return words(line)[0] != "TRYLEARN";
}

std::optional<std::string> readBackLine(std::string_view line) {
  if (roleForCommand(line) != Role::kEngineer) return std::nullopt;
  const auto w = words(line);
  const std::string& command = w[0];
  if ((command == "TOLERANCE" || command == "GRASP" || command == "GRIPPER") && w.size() > 2) {
    // The type must be a number: anything else is the app's to refuse.
    if (w[1].find_first_not_of("0123456789") != std::string::npos || w[1].size() > 9)
      return std::nullopt;
    return command == "TOLERANCE" ? command + " " + w[1] : command + " " + w[1] + " LIST";
  }
  if (command == "EXPOSURE" || command == "ROI" || command == "CAMMODE" || command == "VISION")
    return command;
  // The job in force, and the jobs stored.
  if (command == "JOB" && w.size() > 1) return std::string(w[1] == "LOAD" ? "JOB" : "JOB LIST");
  return std::nullopt;
}

Role roleForCameraAction(std::string_view action) {
  // A software trigger takes a frame, as LOCATE does; everything else
  // changes how the camera works.
  return action == "trigger" ? Role::kOperator : Role::kEngineer;
}

}  // namespace picksight::web
