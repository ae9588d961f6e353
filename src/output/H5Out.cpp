#include <spall/output/H5Out.h>

#include <spall/core/Error.h>

#include <hdf5.h>

#include <filesystem>
#include <mutex>
#include <unistd.h>

namespace spall {

void initialiseHdf5()
{
    static std::once_flag once;
    std::call_once(once, [] {
        H5dont_atexit();
        H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    });
}

H5Out::H5Out(const std::string& path) : mPath(path)
{
    initialiseHdf5();
    mFile = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (mFile < 0) throw IoError(path + ": cannot create");
}

H5Out::~H5Out()
{
    for (auto it = mGroups.rbegin(); it != mGroups.rend(); ++it) H5Gclose(*it);
    if (mFile >= 0) H5Fclose(mFile);
}

int64_t H5Out::checked(int64_t id, const std::string& what) const
{
    if (id < 0) throw IoError(mPath + ": writing " + what + " failed");
    return id;
}

void H5Out::group(const char* name) { mGroups.push_back(checked(H5Gcreate2(mFile, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name)); }

void H5Out::write(const char* name, const std::vector<double>& values, size_t cols)
{
    dataset(name, H5T_NATIVE_DOUBLE, values.data(), values.size(), cols);
}

void H5Out::write(const char* name, const std::vector<int64_t>& values, size_t cols)
{
    dataset(name, H5T_NATIVE_INT64, values.data(), values.size(), cols);
}

void H5Out::attribute(const char* name, double value) { scalar(".", name, H5T_NATIVE_DOUBLE, &value); }

void H5Out::attribute(const char* name, int64_t value) { scalar(".", name, H5T_NATIVE_INT64, &value); }

void H5Out::attribute(const char* object, const char* name, double value) { scalar(object, name, H5T_NATIVE_DOUBLE, &value); }

void H5Out::attribute(const char* object, const char* name, int64_t value) { scalar(object, name, H5T_NATIVE_INT64, &value); }

void H5Out::close()
{
    for (auto it = mGroups.rbegin(); it != mGroups.rend(); ++it) H5Gclose(*it);
    mGroups.clear();
    const herr_t status = H5Fclose(mFile);
    mFile = -1;
    if (status < 0) throw IoError(mPath + ": cannot close");
}

void H5Out::dataset(const char* name, int64_t type, const void* data, size_t count, size_t cols)
{
    const hsize_t dims[2] = {count / cols, cols};
    const hid_t space = checked(H5Screate_simple(cols > 1 ? 2 : 1, dims, nullptr), name);
    const hid_t set = checked(H5Dcreate2(mFile, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name);
    const herr_t status = count ? H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) : 0;
    H5Dclose(set);
    H5Sclose(space);
    checked(status, name);
}

void H5Out::scalar(const char* object, const char* name, int64_t type, const void* value)
{
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attr = checked(H5Acreate_by_name(mFile, object, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name);
    const herr_t status = H5Awrite(attr, type, value);
    H5Aclose(attr);
    H5Sclose(space);
    checked(status, name);
}

void writeH5FileAtomically(const std::string& path, const std::function<void(H5Out&)>& fill)
{
    const std::string partial = path + ".partial." + std::to_string(getpid());
    try {
        {
            H5Out h5(partial);
            fill(h5);
            h5.close();
        }
        std::filesystem::rename(partial, path);
    } catch (...) {
        std::error_code ignored;
        std::filesystem::remove(partial, ignored);
        throw;
    }
}

}  // namespace spall
