// Robot protocol command for jobs: JOB [SAVE|LOAD|LIST|DELETE|EXPORT|IMPORT]
// (docs/PROTOCOL.md).
#pragma once

#include "picksight/jobs/job_switch.hpp"
#include "picksight/protocol/command_table.hpp"

namespace picksight::protocol {

// The largest piece of a job file one JOB EXPORT reply carries (before
// base64), and one JOB IMPORT request may (a request line is at most
// 4096 bytes).
constexpr size_t kJobExportPiece = size_t{1} << 20;
constexpr size_t kJobImportPiece = 2880;

// Registers JOB; `jobs` outlives `table`.
void addJobCommands(CommandTable& table, jobs::JobSwitch& jobs);

}  // namespace picksight::protocol
