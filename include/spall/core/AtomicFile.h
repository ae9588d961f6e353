// Files that are whole or absent: a run interrupted or out of disk space never leaves a partial
// file looking complete.
#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace spall {

/// Writes `path` whole or not at all: `write` fills a binary stream to a temporary beside it
/// (PATH.partial.<pid>), which is checked after closing and renamed over PATH. On any failure
/// the temporary is removed and IoError names PATH and the reason (disk full, not writable).
void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write);

}  // namespace spall
