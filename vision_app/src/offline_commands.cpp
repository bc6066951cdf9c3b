// Offline subcommands over image files.
#include "picksight/vision_app/offline_commands.hpp"

#include <opencv2/imgcodecs.hpp>

#include <ostream>

#include "picksight/common/text.hpp"
#include "picksight/vision_app/app_options.hpp"
#include "picksight/vision_app/command_table.hpp"
#include "picksight/vision_app/model_commands.hpp"
#include "picksight/vision_app/model_library.hpp"
#include "picksight/vision_app/vision_service.hpp"

namespace picksight::app {

std::string offlineUsage() {
  return "usage: picksight-vision learn --type N [--name NAME] [options] IMAGE\n"
         "       picksight-vision locate [--type N] [options] IMAGE...\n"
         "       picksight-vision blobs [options] IMAGE...\n"
         "\n"
         "  learn   trains type N from the single part in IMAGE into DATA_DIR/models\n"
         "  locate  prints one 'OK <n> x y rz ...' line per image: parts of type N\n"
         "          (all trained types without --type; every region without models)\n"
         "  blobs   prints one BLOBS reply line per image\n"
         "Options: --data-dir DIR, --threshold, --polarity, --window, --min-area as in server "
         "mode.\n";
}

bool isOfflineCommand(const std::vector<std::string>& args) {
  return !args.empty() && (args[0] == "learn" || args[0] == "locate" || args[0] == "blobs");
}

int runOfflineCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  if (!isOfflineCommand(args)) {
    err << offlineUsage();
    return 2;
  }
  const std::string command = args[0];
  std::vector<std::string> rest;
  std::vector<std::string> images;
  int type = -1;
  std::string name;
  for (size_t i = 1; i < args.size(); ++i) {
    const std::string& a = args[i];
    if ((a == "--type" || a == "--name") && i + 1 < args.size()) {
      const std::string& v = args[++i];
      if (a == "--name") {
        name = v;
        continue;
      }
      const auto t = parseType(v);
      if (!t) {
        err << "picksight-vision " << command << ": --type must be an integer in [0, 9999], got '"
            << v << "'\n";
        return 2;
      }
      type = *t;
    } else if (a.rfind("--", 0) == 0) {
      rest.push_back(a);
      if (i + 1 < args.size()) rest.push_back(args[++i]);
    } else {
      images.push_back(a);
    }
  }
  auto options = parseAppArgs(rest, nullptr);
  if (!options) {
    err << "picksight-vision " << command << ": " << options.error().message << "\n\n"
        << offlineUsage();
    return 2;
  }
  if (images.empty() || (command == "learn" && (images.size() != 1 || type < 0))) {
    err << offlineUsage();
    return 2;
  }
  ModelLibrary library(options->data_dir + "/models");
  for (const auto& problem : library.load())
    err << "picksight-vision: model rejected: " << problem << "\n";

  int status = 0;
  for (const auto& path : images) {
    const cv::Mat grey = cv::imread(path, cv::IMREAD_GRAYSCALE);
    if (grey.empty()) {
      out << errorReply(kBadArguments, "cannot read image '" + printable(path, 200) + "'") << "\n";
      status = 1;
      continue;
    }
    if (command == "learn") {
      if (name.empty()) name = "type" + std::to_string(type);
      if (!validModelName(name)) {
        err << "picksight-vision learn: name must be 1-32 of A-Z a-z 0-9 _ - .\n";
        return 2;
      }
      vision::TrainOptions train;
      train.binarize = options->vision.binarize;
      train.regions = options->vision.regions;
      const auto outcome = vision::trainModel(grey, type, name, train);
      if (!outcome.ok) {
        const bool none = outcome.error.rfind("no part", 0) == 0;
        out << errorReply(none ? kNoPartToLearn : kSeveralParts, outcome.error) << "\n";
        return 1;
      }
      auto stored = library.store(outcome.model);
      if (!stored) {
        out << errorReply(kStorageFailed, "cannot store the model: " + stored.error().message)
            << "\n";
        return 1;
      }
      out << "OK " << modelSummary(outcome.model) << " "
          << (outcome.model.body.mirror_symmetric ? "1" : "0") << "\n";
    } else if (command == "locate") {
      const auto models = library.snapshot();
      const auto parts = locateInImage(grey, FrameMapping{}, options->vision, *models, type);
      std::string line = "OK " + std::to_string(parts.size());
      for (const auto& p : parts) {
        line += " " + formatFixed(p.x) + " " + formatFixed(p.y) + " " + formatFixed(p.angle_deg);
      }
      out << line << "\n";
    } else {
      const auto blobs = blobsInImage(grey, options->vision);
      std::string line = "OK " + std::to_string(blobs.size());
      for (const auto& b : blobs) line += " " + blobSummary(b);
      out << line << "\n";
    }
  }
  return status;
}

}  // namespace picksight::app
