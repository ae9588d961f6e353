#include "MeshHeader.h"

#include <spall/core/Error.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace spall {

namespace {

std::string lowerExtension(const std::string& path)
{
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

[[noreturn]] void tooMany(const std::string& path, const std::string& declared, uintmax_t neededBytes, uintmax_t fileBytes)
{
    std::ostringstream message;
    message << path << ": the header declares " << declared << ", which needs at least " << neededBytes << " bytes; the file has "
            << fileBytes << " (truncated or corrupt)";
    throw InputError(message.str());
}

/// OFF: "OFF" then the vertex, face and edge counts; a vertex line takes at least 6 bytes
/// ("0 0 0\n"), a face line at least 8 ("3 0 1 2\n").
void checkOff(const std::string& path, uintmax_t fileBytes)
{
    std::ifstream in(path);
    std::string token;
    in >> token;
    if (token.find("OFF") == std::string::npos || token.find("BINARY") != std::string::npos) return;
    // Comments may sit between the keyword and the counts.
    while (in >> std::ws && in.peek() == '#') std::getline(in, token);
    long double vertices = -1, faces = -1;
    if (!(in >> vertices >> faces)) return;  // the reader reports a malformed header itself
    if (vertices < 0 || faces < 0) throw InputError(path + ": the header declares a negative vertex or face count");
    const long double needed = 6.0L * vertices + 8.0L * faces;
    if (needed > static_cast<long double>(fileBytes))
        tooMany(path, std::to_string(static_cast<unsigned long long>(vertices)) + " vertices and " +
                          std::to_string(static_cast<unsigned long long>(faces)) + " faces",
                static_cast<uintmax_t>(std::min(needed, 1e30L)), fileBytes);
}

/// PLY: a header that ends and declares vertices; every element takes at least one byte per
/// property in binary, two ("0 ") in ASCII.
void checkPly(const std::string& path, uintmax_t fileBytes)
{
    std::ifstream in(path);
    std::string line;
    if (!std::getline(in, line) || line.rfind("ply", 0) != 0) return;
    bool ascii = false;
    long double needed = 0, count = 0;
    int properties = 0;
    std::string declared;
    auto closeElement = [&] { needed += count * properties * (ascii ? 2 : 1); };
    bool ended = false, declaresVertices = false;
    while (!ended && std::getline(in, line)) {
        while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
        ended = line == "end_header";
        std::istringstream words(line);
        std::string keyword, name;
        words >> keyword;
        if (keyword == "format") {
            words >> name;
            ascii = name == "ascii";
        } else if (keyword == "element") {
            closeElement();
            words >> name >> count;
            declaresVertices = declaresVertices || name == "vertex";
            if (count < 0) throw InputError(path + ": the header declares a negative count of " + name);
            properties = 0;
            declared += (declared.empty() ? "" : ", ") + std::to_string(static_cast<unsigned long long>(count)) + " " + name;
        } else if (keyword == "property") {
            ++properties;
        }
    }
    // assimp's PLY reader can spin forever on a header it cannot end (found by fuzz_mesh).
    if (!ended) throw InputError(path + ": the PLY header has no end_header line");
    if (!declaresVertices) throw InputError(path + ": the PLY header declares no vertex element");
    closeElement();
    if (needed > static_cast<long double>(fileBytes)) tooMany(path, declared, static_cast<uintmax_t>(std::min(needed, 1e30L)), fileBytes);
}

/// Binary STL: an 80-byte header, a 4-byte triangle count, 50 bytes per triangle. A file that
/// begins with "solid" may be ASCII and is left to the reader.
void checkStl(const std::string& path, uintmax_t fileBytes)
{
    std::ifstream in(path, std::ios::binary);
    char header[84] = {};
    if (!in.read(header, sizeof header)) return;
    if (std::string(header, 5) == "solid") return;
    uint32_t triangles = 0;
    for (int i = 3; i >= 0; --i) triangles = (triangles << 8) | static_cast<unsigned char>(header[80 + i]);  // little endian
    const uintmax_t needed = 84 + 50 * static_cast<uintmax_t>(triangles);
    if (needed > fileBytes) tooMany(path, std::to_string(triangles) + " triangles", needed, fileBytes);
}

}  // namespace

void checkDeclaredCounts(const std::string& path)
{
    std::error_code ec;
    const uintmax_t fileBytes = std::filesystem::file_size(path, ec);
    if (ec) return;  // the reader names the problem
    const std::string ext = lowerExtension(path);
    if (ext == ".off") checkOff(path, fileBytes);
    if (ext == ".ply") checkPly(path, fileBytes);
    if (ext == ".stl") checkStl(path, fileBytes);
}

}  // namespace spall
