// The git commit the executables were built from, for run summaries and reports.
#pragma once

namespace isplat {

// The source tree's commit at build time (12 hex digits), with "-dirty" when tracked files had uncommitted
// changes, or "unknown" when the tree was not a git checkout.
const char* build_commit();

}  // namespace isplat
