#include <spall/output/ViewerPage.h>

#include "ViewerAssets.h"

#include <spall/core/AtomicFile.h>
#include <spall/core/Error.h>

#include <boost/archive/iterators/base64_from_binary.hpp>
#include <boost/archive/iterators/transform_width.hpp>

#include <algorithm>
#include <fstream>
#include <functional>
#include <iterator>
#include <sstream>
#include <string_view>
#include <vector>

namespace spall {

namespace {

std::vector<char> readWhole(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path + ": cannot read (run spall export gltf first)");
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// RFC 4648 base64 with '=' padding, by Boost.Serialization's 6-bit re-chunking iterators.
void writeBase64(std::ostream& out, const std::vector<char>& bytes)
{
    using namespace boost::archive::iterators;
    using Encoder = base64_from_binary<transform_width<std::vector<char>::const_iterator, 6, 8>>;
    std::copy(Encoder(bytes.begin()), Encoder(bytes.end()), std::ostreambuf_iterator<char>(out));
    out << std::string((3 - bytes.size() % 3) % 3, '=');
}

std::string htmlEscaped(const std::string& text)
{
    std::string escaped;
    for (const char c : text) {
        switch (c) {
        case '&': escaped += "&amp;"; break;
        case '<': escaped += "&lt;"; break;
        case '>': escaped += "&gt;"; break;
        case '"': escaped += "&quot;"; break;
        default: escaped += c;
        }
    }
    return escaped;
}

}  // namespace

size_t writeViewerPage(const std::string& glbPath, const std::string& htmlPath, const std::string& title)
{
    const std::vector<char> glb = readWhole(glbPath);
    size_t bytes = 0;
    writeFileAtomically(htmlPath, [&](std::ostream& out) {
        std::string_view page = viewer_assets::kPageTemplate;
        // Each placeholder in the order the template holds them, and what replaces it.
        const std::pair<std::string_view, std::function<void()>> fills[] = {
            {"@SPALL_TITLE@", [&] { out << htmlEscaped(title); }},
            {"@SPALL_GLB_BASE64@", [&] { writeBase64(out, glb); }},
            {"@SPALL_VIEWER_JS@", [&] { out << viewer_assets::kScript; }},
        };
        for (const auto& [placeholder, fill] : fills) {
            const size_t at = page.find(placeholder);
            if (at == std::string_view::npos) throw IoError("viewer page template lacks " + std::string(placeholder));
            out << page.substr(0, at);
            fill();
            page.remove_prefix(at + placeholder.size());
        }
        out << page;
        bytes = size_t(out.tellp());
    });
    return bytes;
}

}  // namespace spall
