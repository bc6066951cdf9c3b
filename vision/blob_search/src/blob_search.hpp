// The search of one merged blob for the parts inside it (locateInBlob), as
// named stages a test can run one at a time. Not installed: only
// touching_parts.cpp and the blob search's stage tests include it.
//
//   BlobSearch(...)     the models that fit in the blob; its edge map,
//                       corners and arcs, and pixels
//   screen(model, ...)  a model's poses proposed from the anchors, best
//                       first, no two alike
//   refine(screened)    each screened pose fitted on the grey-level edges
//                       (within the blob's budget of edge fits), and placed
//                       where it fits the blob on its own (place)
//   choose()            the parts among those placed (best first, rivals
//                       for the same pixels settled, mirror images refused)
//   explainsWhole()     whether the parts taken are the whole blob
//   narrowToRest()      the anchors the full search starts from: those near
//                       what the parts taken leave unexplained
//   readRest()          what the parts taken leave, read as a lone region:
//                       one whole untaught copy of a type (its mirror
//                       image, a larger copy: nothing more to search for),
//                       one part of a model, or neither
//   settleRest()        ends the search beside such a copy; places such a
//                       part from the reading's pose
//   searchRestMiddle()  each model the size of what is left unexplained,
//                       put on its middle and turned (proposeAbout): a part
//                       whose corners its outline does not show as the
//                       model's; with nothing found, also the rest's other
//                       pieces and those its largest parts into at its
//                       necks, each about its own middle
//   run()               the stages in order: a quick search of every model,
//                       then while the blob is not explained whole (and
//                       what is left no whole copy) the rest settled, the
//                       full search, model by model, and the search of
//                       the rest's middle
#pragma once

#include <deque>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "picksight/vision/blob_search/touching_parts.hpp"
#include "picksight/vision/models/boundary_verification.hpp"
#include "picksight/vision/models/match.hpp"
#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/segmentation/regions.hpp"
#include "touching_parts_internal.hpp"

namespace picksight::vision::touching {

// A refined candidate that fits the blob on its own, drawn over its box.
struct Placed {
  const Candidate* candidate = nullptr;
  cv::Rect box;   // image coordinates
  cv::Mat drawn;  // 255 on the part, over `box`
  int area = 0;
};

class BlobSearch {
 public:
  // The search of region `index` of `regions` with `models` (see
  // locateInBlob; `built_edges` may be null). Selects the models that fit in
  // the blob and, when any does, reads the blob: its edge map (unless given),
  // corners and arcs, and pixels. Keeps references to all arguments.
  BlobSearch(const std::vector<Region>& regions, size_t index,
             const std::vector<const PartModel*>& models, const EdgeDistance* built_edges,
             const LoneRegionTest* read_rest = nullptr);
  BlobSearch(const BlobSearch&) = delete;
  BlobSearch& operator=(const BlobSearch&) = delete;

  // The stages in order; the parts found, best score first.
  std::vector<Match> run();

  // The models no larger than the blob (empty: nothing to search, also
  // where the blob's outline is nowhere a step: a patch of the surface).
  const std::vector<const PartModel*>& fitting() const { return fitting_; }
  // The blob's corners and arcs the next screening starts from.
  const BlobCorners& corners() const { return *corners_; }
  const std::vector<ArcAnchor>& arcs() const { return *arcs_; }

  // The best screened poses of one model (its own hand: see alignedMirror),
  // best first, no two alike, from its `anchors`. `whole`, when given: set
  // to whether every pose the screening found was kept (none beyond the
  // kMaxRefinedPerModel best).
  std::vector<Candidate> screen(const PartModel& model, Anchors anchors,
                                bool* whole = nullptr) const;
  // Refines screened poses, best first, and places those that fit.
  void refine(const std::vector<Candidate>& screened);
  // Places a refined candidate (kept by the caller for the search's
  // lifetime) where it fits the blob on its own; false where it does not.
  bool place(const Candidate& candidate);
  // Takes the parts among those placed.
  void choose();
  // Whether the parts taken are the whole blob: each fits its edges closely,
  // and together they cover it (coversBlob).
  bool explainsWhole() const;
  // Whether the parts taken cover every pixel of the blob but a seam up to
  // `seam_px` wide.
  bool coversBlob(int seam_px) const;
  // Turns the next screenings to the anchors near the blob's pixels that the
  // parts taken leave unexplained (when any remain past a seam). Returns
  // the area of those pixels (at least 1).
  double narrowToRest();
  // Whether the part at `candidate` shows its model's mirror image (asked
  // of a candidate about to be taken; the aligned mirror image is fitted
  // once per candidate).
  bool showsMirror(const Candidate& candidate);
  // What the parts taken leave of the blob, where it is one piece (after an
  // opening by the seam), read by the lone-region test (see locateInBlob):
  // an untaught copy of a type (the search then ends), one part, or
  // neither. Neither without the test, with no part taken, for a blob the
  // frame cuts, and where the rest's outline is not the blob's
  // (kWholeOutlineShare: a part the parts taken lie over). Asked again with
  // the same parts taken, the same reading (kPart's turn is about the
  // piece's centroid, kept with it).
  LoneReading readRest();
  // True where the search is over: what is left is a whole copy, or reads
  // as one part which, refined from the reading's pose and taken by
  // choose(), leaves the blob explained whole. A part a blob search would
  // otherwise find screening model after model.
  bool settleRest();
  // The models of the size of the largest piece the parts taken leave, each
  // turned about its middle; where nothing is taken then, the two models
  // nearest the size of each other piece, and of each piece the largest
  // parts into at its necks (when it has room for two parts), about its
  // middle. Refines what it proposes (choose() takes it).
  void searchRestMiddle();

  const std::deque<Candidate>& refined() const { return refined_; }
  const std::vector<Placed>& placed() const { return placed_; }
  // Indices into placed() of the parts taken by the last choose().
  const std::vector<size_t>& taken() const { return taken_; }
  // The parts taken, as matches.
  std::vector<Match> matches() const;

 private:
  // Whether more of the boundary of `m` at `pose` than a part can show lies
  // off the edges on the background, and not on a faint part the mask lost
  // nor on a stretch of the part too thin to show (kMaxOnBackground,
  // FaintPart, kThinHalfWidthPx).
  bool crossesBackground(const PartModel& m, const ImagePose& pose);
  // The share of the boundary of `m` at `pose` on the blob's outline (see
  // kMinOnOutline).
  double onOutline(const PartModel& m, const ImagePose& pose);
  // The blob's pixels the parts taken leave unexplained (over its box).
  cv::Mat unexplained() const;
  // The blob's pixels in `box` that `drawn` (over `box`) covers.
  int coveredIn(const cv::Mat& drawn, const cv::Rect& box) const;
  // The full search after the quick one: `order` holds per model (index
  // into fitting()) what the quick search saw of it.
  void fullSearch(std::vector<std::pair<double, size_t>> order);
  // Each model turned about its point (proposeAbout), all at once, then the
  // poses refined best first. `from_core`: each point is where the part's
  // deepest core lies (proposeAbout).
  void searchAbout(const std::vector<std::pair<const PartModel*, cv::Point2d>>& sized,
                   bool from_core = false);
  // The distance map of the blob's outline, exact up to `reach`.
  EdgeDistance edgeMap(double reach) const;

  const Region& region_;
  size_t index_;
  const LoneRegionTest* read_rest_ = nullptr;
  // The parts taken when readRest was last asked, its reading, and the
  // centroid of the piece it read.
  struct RestRead {
    std::vector<size_t> taken;
    LoneReading reading;
    cv::Point2d centre;
  };
  std::optional<RestRead> rest_read_;
  std::vector<const PartModel*> fitting_;
  double tolerance_ = 0;     // the largest edge tolerance of the fitting models
  double conformity_ = 1e9;  // their smallest conformity
  std::optional<EdgeDistance> own_edges_;
  const EdgeDistance* edges_ = nullptr;
  std::optional<BlobCorners> all_corners_;
  std::vector<ArcAnchor> image_arcs_;
  std::optional<BlobCorners> rest_corners_;
  std::vector<ArcAnchor> rest_arcs_;
  const BlobCorners* corners_ = nullptr;
  const std::vector<ArcAnchor>* arcs_ = nullptr;
  cv::Rect blob_box_;
  cv::Mat blob_;  // 255 on the blob's pixels, over blob_box_
  std::optional<Coverage> coverage_;
  std::optional<FaintPart> faint_;  // made when a pose first crosses without it
  // Distance to the blob's outline and large holes (see onOutline): empty
  // when that is every edge (edges_); made when first asked.
  std::optional<EdgeDistance> outline_;
  // The wide map the searches about a point read (searchAbout): the same
  // for each of them, made when first asked (a sixth of each search's
  // time went to making it).
  std::optional<EdgeDistance> about_map_;
  int blob_pixels_ = 0;
  size_t budget_ = 0;  // edge fits the blob may cost
  cv::Mat seam_;       // what erodes a seam away
  // Refined poses (a deque: the placed ones point into it), and those that
  // fit the blob on their own.
  std::deque<Candidate> refined_;
  std::vector<Placed> placed_;
  size_t refinements_ = 0;
  // Per model (as fitting_): whether its quick screening kept every pose it
  // found, so that the full search need not start from its quick anchors.
  // (chars: the quick screenings write them from several threads at once.)
  std::vector<char> quick_whole_;
  // Whether a choice made now could differ from the last one.
  bool changed_ = false;
  std::map<const Candidate*, std::optional<Candidate>> aligned_mirrors_;
  std::vector<size_t> taken_;
};

}  // namespace picksight::vision::touching
