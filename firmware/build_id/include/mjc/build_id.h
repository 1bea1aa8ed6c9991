// The build's identity, from git at build time (cmake/build_id.cmake): what a board
// reports in its BoardInfo and what `mjc --version` prints, so a lab can tell which
// firmware a board runs.
#pragma once

#include <cstdint>

namespace mjc::build {

// `git describe --always --dirty`: a tag or commit, "-dirty" when the tree had
// uncommitted changes; "unknown" outside a git checkout.
extern const char kDescribe[];
// The commit's hash, its first 32 bits (8 hex digits); 0 when unknown.
extern const std::uint32_t kCommit;
extern const bool kDirty;
// The commit's time (seconds since 1970), not the build's: a rebuild of one commit gives
// the same image.
extern const std::uint32_t kCommitTimeUnix;

}  // namespace mjc::build
