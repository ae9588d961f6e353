#include <spall/core/AtomicFile.h>

#include <spall/core/Error.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace spall {

void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write)
{
    // The pid keeps two processes writing the same path from sharing a temporary.
    const std::string temporary = path + ".partial." + std::to_string(::getpid());
    const auto discard = [&] {
        std::error_code ec;
        std::filesystem::remove(temporary, ec);
    };
    try {
        std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
        if (!out) throw IoError(path + ": cannot create " + temporary + " (not writable?)");
        write(out);
        out.flush();
        out.close();
        if (out.fail()) throw IoError(path + ": cannot write (disk full or not writable?); nothing was left in its place");
    } catch (const IoError&) {
        discard();
        throw;
    } catch (const std::exception& e) {
        discard();
        throw IoError(path + ": cannot write: " + e.what());
    }
    std::error_code ec;
    std::filesystem::rename(temporary, path, ec);
    if (ec) {
        discard();
        throw IoError(path + ": cannot rename the finished file into place: " + ec.message());
    }
}

}  // namespace spall
