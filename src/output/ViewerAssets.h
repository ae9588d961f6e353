// The debris viewer's page template and bundled script, compiled into the library from
// tools/js/viewer by cmake/EmbedViewer.cmake.
#pragma once

namespace spall::viewer_assets {

/// HTML with the placeholders @SPALL_TITLE@, @SPALL_GLB_BASE64@ and @SPALL_VIEWER_JS@.
extern const char* const kPageTemplate;
/// tools/js/viewer/viewer.js with three.js, bundled and minified by esbuild.
extern const char* const kScript;

}  // namespace spall::viewer_assets
