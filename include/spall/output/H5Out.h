// A small HDF5 file written in one go (analysis reports, sweep summaries): groups, whole
// datasets and scalar attributes, written under a temporary name and renamed, so the file is
// whole or absent. history.h5, which grows frame by frame, has its own writer (output/History.h).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace spall {

/// Once per process, before any other HDF5 call: errors become IoError instead of stderr noise,
/// and HDF5 does not close files from an exit handler (after a failed write it would crash
/// there; the writers close their files themselves).
void initialiseHdf5();

class H5Out {
public:
    explicit H5Out(const std::string& path);
    ~H5Out();
    H5Out(const H5Out&) = delete;
    H5Out& operator=(const H5Out&) = delete;

    void group(const char* name);
    /// A dataset of rows × cols (1-D when cols is 1), from row-major values.
    void write(const char* name, const std::vector<double>& values, size_t cols = 1);
    void write(const char* name, const std::vector<int64_t>& values, size_t cols = 1);
    /// A scalar attribute of the file's root, or of the group or dataset `object` (a path).
    void attribute(const char* name, double value);
    void attribute(const char* name, int64_t value);
    void attribute(const char* object, const char* name, double value);
    void attribute(const char* object, const char* name, int64_t value);
    /// Closes the file; throws IoError naming it when HDF5 cannot finish it.
    void close();

private:
    int64_t checked(int64_t id, const std::string& what) const;
    void dataset(const char* name, int64_t type, const void* data, size_t count, size_t cols);
    void scalar(const char* object, const char* name, int64_t type, const void* value);

    std::string mPath;
    int64_t mFile = -1;
    std::vector<int64_t> mGroups;
};

/// Fills `path` through `fill` under a temporary name (PATH.partial.<pid>) and renames it; on any
/// error the temporary is removed and the error passed on.
void writeH5FileAtomically(const std::string& path, const std::function<void(H5Out&)>& fill);

}  // namespace spall
