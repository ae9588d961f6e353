// The growing datasets of history.h5 (output/History.cpp): a chunked, extensible dataset that a
// frame appends rows to, and the checks and attributes around it. Private to output.
#pragma once

#include <spall/core/Error.h>

#include <hdf5.h>

#include <cstring>
#include <string>

namespace spall::history {

inline void check(herr_t status, const std::string& what)
{
    if (status < 0) throw IoError("history.h5: " + what + " failed");
}

inline hid_t checkId(hid_t id, const std::string& what)
{
    if (id < 0) throw IoError("history.h5: " + what + " failed");
    return id;
}

/// One extensible, chunked dataset of rows x cols. Uncompressed on purpose: an uncompressed chunk
/// keeps its place in the file, so appending rewrites the old rows with the same bytes and a run
/// killed in the middle of a write cannot damage the frames before it. (A compressed chunk
/// moves when it grows, and its old place can be handed to another dataset's chunk before the
/// index is updated: a kill then leaves earlier rows unreadable. It was seen in testing.)
class Series {
public:
    Series() = default;
    Series(hid_t parent, const char* name, hid_t type, hsize_t cols, hsize_t chunkRows = 1024) : mType(type), mCols(cols)
    {
        const int rank = cols > 1 ? 2 : 1;
        hsize_t dims[2] = {0, cols}, maxDims[2] = {H5S_UNLIMITED, cols}, chunk[2] = {chunkRows, cols};
        const hid_t space = checkId(H5Screate_simple(rank, dims, maxDims), "dataspace");
        const hid_t plist = checkId(H5Pcreate(H5P_DATASET_CREATE), "property list");
        check(H5Pset_chunk(plist, rank, chunk), "chunking");
        mId = checkId(H5Dcreate2(parent, name, type, space, H5P_DEFAULT, plist, H5P_DEFAULT), std::string("creating ") + name);
        H5Pclose(plist);
        H5Sclose(space);
    }
    /// Opens an existing dataset and cuts it to its first `rows` rows.
    static Series open(hid_t parent, const char* name, hid_t type, hsize_t cols, hsize_t rows)
    {
        Series s;
        s.mType = type;
        s.mCols = cols;
        s.mId = checkId(H5Dopen2(parent, name, H5P_DEFAULT), std::string("opening ") + name);
        const hid_t space = H5Dget_space(s.mId);
        hsize_t dims[2] = {0, cols};
        H5Sget_simple_extent_dims(space, dims, nullptr);
        H5Sclose(space);
        if (dims[0] < rows) throw IoError(std::string("history.h5: ") + name + " has " + std::to_string(dims[0]) + " rows, fewer than the checkpoint's " + std::to_string(rows));
        hsize_t newDims[2] = {rows, cols};
        check(H5Dset_extent(s.mId, newDims), std::string("cutting ") + name);
        s.mRows = rows;
        return s;
    }
    /// One value of a one-column int64 dataset.
    int64_t int64At(hsize_t row) const
    {
        const hid_t file = H5Dget_space(mId);
        hsize_t start[1] = {row}, count[1] = {1};
        check(H5Sselect_hyperslab(file, H5S_SELECT_SET, start, nullptr, count, nullptr), "selecting a row");
        const hid_t memory = H5Screate_simple(1, count, nullptr);
        int64_t value = 0;
        check(H5Dread(mId, H5T_NATIVE_INT64, memory, file, H5P_DEFAULT, &value), "reading a row");
        H5Sclose(memory);
        H5Sclose(file);
        return value;
    }
    void append(const void* data, hsize_t rows)
    {
        if (rows == 0) return;
        const int rank = mCols > 1 ? 2 : 1;
        hsize_t newDims[2] = {mRows + rows, mCols};
        check(H5Dset_extent(mId, newDims), "extending a dataset");
        const hid_t file = H5Dget_space(mId);
        hsize_t start[2] = {mRows, 0}, count[2] = {rows, mCols};
        check(H5Sselect_hyperslab(file, H5S_SELECT_SET, start, nullptr, count, nullptr), "selecting rows");
        const hid_t memory = H5Screate_simple(rank, count, nullptr);
        check(H5Dwrite(mId, mType, memory, file, H5P_DEFAULT, data), "writing rows (disk full?)");
        H5Sclose(memory);
        H5Sclose(file);
        mRows += rows;
    }
    void close()
    {
        if (mId >= 0) H5Dclose(mId);
        mId = -1;
    }

private:
    hid_t mId = -1;
    hid_t mType = -1;
    hsize_t mCols = 1;
    hsize_t mRows = 0;
};

inline void writeStringAttribute(hid_t object, const char* name, const std::string& value)
{
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, value.empty() ? 1 : value.size());
    H5Tset_strpad(type, H5T_STR_NULLTERM);
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attr = checkId(H5Acreate2(object, name, type, space, H5P_DEFAULT, H5P_DEFAULT), name);
    check(H5Awrite(attr, type, value.empty() ? "" : value.c_str()), name);
    H5Aclose(attr);
    H5Sclose(space);
    H5Tclose(type);
}

template <typename T>
void writeScalarAttribute(hid_t object, const char* name, hid_t type, T value)
{
    const hid_t space = H5Screate(H5S_SCALAR);
    hid_t attr = H5Aexists(object, name) > 0 ? H5Aopen(object, name, H5P_DEFAULT)
                                             : H5Acreate2(object, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
    checkId(attr, name);
    check(H5Awrite(attr, type, &value), name);
    H5Aclose(attr);
    H5Sclose(space);
}


}  // namespace spall::history
