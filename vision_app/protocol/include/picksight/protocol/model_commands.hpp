// Robot protocol commands for part models and blob analysis: LEARN, MODELS,
// TRYLEARN, TOLERANCE, FORGET, UNDO, BLOBS (docs/PROTOCOL.md).
#pragma once

#include "picksight/cell/vision_service.hpp"
#include "picksight/protocol/command_table.hpp"

namespace picksight::protocol {

// Registers the commands; `vision` (with its model library) outlives `table`.
void addModelCommands(CommandTable& table, cell::VisionService& vision);

// The reply fields of one model ("<type> <name> <area> <holes> <symmetry>").
std::string modelSummary(const vision::PartModel& model);
// LEARN's reply: "OK <type> <name> <area> <holes> <symmetry> <mirror 0/1>",
// then " ; warning: <text>" for each warning.
std::string learnReply(const cell::LearnOutcome& learned);
// LEARNVIEW's reply: `OK <type> <name> <views> <dx> <dy> <spread> ; note:
// ...` (docs/PROTOCOL.md).
std::string learnViewReply(const cell::ViewOutcome& view);
// TOLERANCE's reply: "OK <type> <name>" then " <key>=<value>" for each
// tolerance a model file stores (area_tolerance, hu_tolerance,
// verify_percent, edge_tolerance_px, mirror_symmetric).
std::string toleranceReply(const vision::PartModel& model);
// TRYLEARN's reply: LEARN's fields, then "<found> <parts>" (the parts of
// the type LOCATE ALL finds on the same frame with the new model, and all
// it finds), LEARN's warnings and notes, and " ; note: nothing stored".
std::string tryLearnReply(const cell::TryLearnOutcome& tried);
// UNDO's reply: "OK <type> restored|removed <changes left> ; undid: <request>
// ; type <type> is <model summary> again" (or "has no model again").
std::string undoReply(const store::UndoOutcome& undone);
// The reply fields of one region's features (see BLOBS).
std::string blobSummary(const vision::BlobFeatures& blob);

// A model name: 1 to 32 of A-Z a-z 0-9 _ - .
bool validModelName(std::string_view name);

}  // namespace picksight::protocol
