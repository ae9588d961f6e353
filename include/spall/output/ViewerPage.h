// A run's debris as one self-contained web page: debris.glb played back with three.js.
#pragma once

#include <cstddef>
#include <string>

namespace spall {

/// Writes `htmlPath` (whole or not at all): a page that plays `glbPath` — inlined as base64, with
/// the viewer script compiled into spall — so it opens from disk with no server or network.
/// `title` names the run in the browser tab. Returns the page's size in bytes.
/// Throws IoError when the .glb cannot be read or the page cannot be written.
size_t writeViewerPage(const std::string& glbPath, const std::string& htmlPath, const std::string& title);

}  // namespace spall
