// Element counts that mesh files declare up front, checked against the file's size before any
// reader allocates for them (a 300-byte file claiming billions of vertices is refused at once).
#pragma once

#include <string>

namespace spall {

/// Throws InputError naming the file, the declared counts and the file's size when an OFF, PLY
/// or binary STL header declares more elements than the file could hold. Other formats pass.
void checkDeclaredCounts(const std::string& path);

}  // namespace spall
