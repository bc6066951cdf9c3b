// The everyday-object silhouette types the recognition benchmarks train, and
// their drawings read from the test data. Header-only: bench code.
#pragma once

#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include "picksight/codecs/codecs.hpp"

#include "picksight/cli/command_line.hpp"
#include "picksight/synthetic/silhouette_scene.hpp"

namespace picksight::bench {

// The benchmarks train each type on its drawing turned by this angle, so
// that the model is made from a part drawn the way every scene part is
// (resampled: the renderer rounds tips and stems finer than its grid,
// except at exactly 0 where it copies the drawing). Trained at 0, thin
// types (palm fronds, a spoon's rim) had sharper tips in their model than
// in any scene, and their edge-fitted poses a constant 0.1 to 0.14 px
// offset in the model's frame.
constexpr double kTrainAngleDeg = 30.0;

// A benchmark type: where its drawing comes from and which family it shows.
struct TypeSpec {
  std::string name;
  std::string file;  // under the data directory; empty: partShape(name)
  std::string family;
  double size_px;  // longest side in the image
};

// Chosen for what breaks recognition: thin stems and tines, long slender
// parts, organic curved outlines, near-symmetric parts, and the repository's
// own shapes as the reference.
inline const std::vector<TypeSpec>& silhouetteTypeSpecs() {
  static const std::vector<TypeSpec> specs = {
      {"tulip", "shapes/tari1000/obj16_1.png", "thin", 260},
      {"spoon", "shapes/tari1000/obj29_1.png", "thin", 240},
      {"twig", "shapes/tari1000/obj43_1.png", "thin", 280},
      {"palm", "shapes/tari1000/obj10_1.png", "thin", 250},
      {"bottle", "shapes/tari1000/obj32_1.png", "slender", 230},
      {"stick", "shapes/tari1000/obj50_1.png", "slender", 260},
      {"bone", "shapes/kimia99/trainimage9_1.png", "slender", 240},
      {"turtle", "shapes/tari1000/obj4_1.png", "curved", 200},
      {"frog", "shapes/tari1000/obj20_1.png", "curved", 220},
      {"blob", "shapes/tari1000/obj7_1.png", "curved", 180},
      {"star", "shapes/tari1000/obj2_1.png", "near-symmetric", 200},
      {"bell", "shapes/tari1000/obj41_1.png", "near-symmetric", 190},
      {"gear", "", "own", 170},
      {"l_shape", "", "own", 180},
      {"slot", "", "own", 170},
  };
  return specs;
}

// Drawings for types a cell knows beyond the scene's (a product line's
// variants: what recognition costs as a cell learns more types): classes of the two sets
// that no scene type comes from (the first drawing of each, then the fifth,
// a different drawing of the same class), at sizes spread over the scene
// types' range. Trained, never drawn: every part they are reported on is
// a false report.
inline std::vector<TypeSpec> untaughtTypeSpecs(const std::vector<TypeSpec>& scene, size_t count) {
  std::set<std::string> used;
  for (const auto& s : scene) {
    if (!s.file.empty()) used.insert(s.file.substr(0, s.file.rfind('_')));
  }
  std::vector<std::string> classes;
  for (int i = 1; i <= 50; ++i) classes.push_back("shapes/tari1000/obj" + std::to_string(i));
  for (int i = 1; i <= 9; ++i) classes.push_back("shapes/kimia99/trainimage" + std::to_string(i));
  std::vector<TypeSpec> extra;
  for (const char* drawing : {"_1.png", "_5.png"}) {
    for (const auto& c : classes) {
      if (extra.size() >= count) return extra;
      if (used.count(c)) continue;
      const std::string name = c.substr(c.rfind('/') + 1) + drawing;
      const double size = 160 + static_cast<double>((extra.size() * 37) % 120);
      extra.push_back({name.substr(0, name.rfind('.')), c + drawing, "untaught", size});
    }
  }
  return extra;
}

// The types of `specs`, drawings read under `data_dir`. False, with a
// message, when a drawing cannot be read.
inline bool loadSilhouetteTypes(const std::vector<TypeSpec>& specs, const std::string& data_dir,
                                std::vector<synthetic::SilhouetteType>* types) {
  for (const auto& spec : specs) {
    if (spec.file.empty()) {
      types->push_back(synthetic::silhouetteFromPartType(spec.name, spec.size_px));
      continue;
    }
    const cv::Mat drawing =
        picksight::codecs::imread(data_dir + "/" + spec.file, cv::IMREAD_GRAYSCALE);
    if (drawing.empty()) {
      std::fprintf(stderr, "cannot read %s/%s (--data DIR)\n", data_dir.c_str(), spec.file.c_str());
      return false;
    }
    types->push_back(synthetic::silhouetteFromDrawing(spec.name, drawing, spec.size_px));
  }
  return true;
}

// The scenes' frame size and part count as options (--width --height
// --parts): 4000 x 3000 with 80 parts is a 12 MP camera's.
inline void addSceneSizeOptions(cli::App& app, synthetic::SilhouetteSceneOptions& look) {
  app.addOption("--width", look.width,
                "frame width, px (4000 with --height 3000 --parts 80: 12 MP)")
      ->check(cli::range(640, 8192))
      ->showDefault();
  app.addOption("--height", look.height, "frame height, px")
      ->check(cli::range(480, 8192))
      ->showDefault();
  app.addOption("--parts", look.parts, "parts a scene (distractors included)")
      ->check(cli::range(1, 400))
      ->showDefault();
}
}  // namespace picksight::bench
