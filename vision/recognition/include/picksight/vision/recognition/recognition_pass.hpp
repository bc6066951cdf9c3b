// Recognition of one frame's regions as the cell runs it (the robot's
// LOCATE and LOCATE <type>, the PLC's trigger, the offline CLI): each model judges
// the regions with its own minimum hole area (the one it was trained with),
// and `LOCATE <type>` recognizes with that type's models alone but drops a
// part that a cheap screen across every type (area, hole count, Hu
// distance; no pose search) finds clearly closer to another type's model.
//
// Threading: pure functions; the models and regions are only read.
#pragma once

#include <vector>

#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/recognition/recognizer.hpp"
#include "picksight/vision/segmentation/regions.hpp"

namespace picksight::vision {

// The region settings that let every model of `models` see what it was
// trained to see: the smallest minimum hole and region areas among the
// cell's (`cell`) and the models' own (frame pixels, all of them); and the
// regions at the frame's edge as large as a part of a model kept, for the
// parts they may hold whole (recognize searches them as blobs).
RegionOptions regionOptionsFor(const RegionOptions& cell, const std::vector<PartModel>& models);

// The smallest region worth a look when every type is known: a share of the
// smallest model's area (frame pixels; 0 with no models). Anything smaller is
// a speck (a belt's grain, dust, a glint's rim) that no model can be, and
// costs a region pass and a WHY line for nothing.
double speckAreaFor(const std::vector<PartModel>& models);

// Why a region left out of `LOCATE <type>` by the screen is not the asked type.
struct ScreenedOut {
  size_t region = 0;
  const PartModel* asked = nullptr;   // the asked type's model it passed
  const PartModel* closer = nullptr;  // the other type's model it is closer to
  double asked_distance = 0;          // Hu distance over the asked model's Hu tolerance
  double closer_distance = 0;         // the same for the closer model
};

struct RecognitionPass {
  std::vector<Match> matches;  // best score first
  std::vector<ScreenedOut> screened_out;
};

// The parts among `regions` (found with regionOptionsFor(..., models)) of
// type `type` (-1: every type competes for every region), each model
// judging hole counts with its own minimum hole area.
RecognitionPass recognizeParts(const std::vector<Region>& regions,
                               const std::vector<PartModel>& models, int type);

}  // namespace picksight::vision
