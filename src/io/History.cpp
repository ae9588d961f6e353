#include <spall/io/History.h>

#include <spall/io/H5Out.h>

#include <spall/core/Error.h>

#include <hdf5.h>

#include <cstring>
#include <filesystem>

namespace spall {

namespace {

void check(herr_t status, const std::string& what)
{
    if (status < 0) throw IoError("history.h5: " + what + " failed");
}

hid_t checkId(hid_t id, const std::string& what)
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

void writeStringAttribute(hid_t object, const char* name, const std::string& value)
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

}  // namespace

struct HistoryWriter::Impl {
    std::string path;
    hid_t file = -1;
    hid_t groups[6] = {-1, -1, -1, -1, -1, -1};
    Series time, bodyOffset, kinetic, linear, angular, broken, steps, minDt, bodyCount, voxelCount, dustMass, latticeParticleSteps, discardedVibration;
    Series id, parent, position, orientation, linVel, angVel, mass, voxels, asleep, anchored;
    Series eventTime, eventParent, eventChildOffset, eventChild;
    Series dustTime, dustParent, dustVoxels, dustMassRows, dustMomentum;
    int64_t bodyRows = 0, childRows = 0;

    /// Throws IoError when the disk cannot take a frame of this size.
    void requireSpaceFor(size_t newBodyRows, const std::vector<FractureEvent>& events, size_t newDustRows) const;
    void appendBodies(const std::vector<BodyRow>& bodies);
    void appendEvents(const std::vector<FractureEvent>& events, const std::vector<DustRecord>& dust);
    void appendFrameRow(const FrameRow& f);
    void flush() { check(H5Fflush(file, H5F_SCOPE_GLOBAL), "flushing (disk full?)"); }
    void close()
    {
        for (Series* s : {&time, &bodyOffset, &kinetic, &linear, &angular, &broken, &steps, &minDt, &bodyCount, &voxelCount, &dustMass,
                          &latticeParticleSteps, &discardedVibration,
                          &id, &parent, &position, &orientation, &linVel, &angVel, &mass, &voxels, &asleep, &anchored, &eventTime,
                          &eventParent, &eventChildOffset, &eventChild, &dustTime, &dustParent, &dustVoxels, &dustMassRows, &dustMomentum})
            s->close();
        for (hid_t& g : groups)
            if (g >= 0) H5Gclose(g), g = -1;
        if (file >= 0) H5Fclose(file);
        file = -1;
    }
};

namespace {

enum Group { kFrames, kBodies, kFracture, kDust };

/// Every growing dataset of the history: where it lives, its type and shape.
struct SeriesSpec {
    Series HistoryWriter::Impl::*member;
    Group group;
    const char* name;
    hid_t type;
    hsize_t cols;
    hsize_t chunkRows;
};

std::vector<SeriesSpec> seriesSpecs()
{
    using I = HistoryWriter::Impl;
    const hid_t d = H5T_NATIVE_DOUBLE, i64 = H5T_NATIVE_INT64, i8 = H5T_NATIVE_INT8;
    return {
        {&I::time, kFrames, "time_s", d, 1, 256},
        {&I::bodyOffset, kFrames, "body_offset", i64, 1, 256},
        {&I::kinetic, kFrames, "kinetic_energy_J", d, 1, 256},
        {&I::linear, kFrames, "linear_momentum_kg_m_s", d, 3, 256},
        {&I::angular, kFrames, "angular_momentum_kg_m2_s", d, 3, 256},
        {&I::broken, kFrames, "broken_links", i64, 1, 256},
        {&I::steps, kFrames, "steps", i64, 1, 256},
        {&I::minDt, kFrames, "min_dt_s", d, 1, 256},
        {&I::bodyCount, kFrames, "body_count", i64, 1, 256},
        {&I::voxelCount, kFrames, "voxel_count", i64, 1, 256},
        {&I::dustMass, kFrames, "dust_mass_kg", d, 1, 256},
        {&I::latticeParticleSteps, kFrames, "lattice_particle_steps", i64, 1, 256},
        {&I::discardedVibration, kFrames, "discarded_vibration_J", d, 1, 256},
        {&I::id, kBodies, "id", i64, 1, 1024},
        {&I::parent, kBodies, "parent_id", i64, 1, 1024},
        {&I::position, kBodies, "position_m", d, 3, 1024},
        {&I::orientation, kBodies, "orientation_wxyz", d, 4, 1024},
        {&I::linVel, kBodies, "linear_velocity_m_s", d, 3, 1024},
        {&I::angVel, kBodies, "angular_velocity_rad_s", d, 3, 1024},
        {&I::mass, kBodies, "mass_kg", d, 1, 1024},
        {&I::voxels, kBodies, "voxel_count", i64, 1, 1024},
        {&I::asleep, kBodies, "asleep", i8, 1, 1024},
        {&I::anchored, kBodies, "anchored", i8, 1, 1024},
        {&I::eventTime, kFracture, "time_s", d, 1, 256},
        {&I::eventParent, kFracture, "parent_id", i64, 1, 256},
        {&I::eventChildOffset, kFracture, "child_offset", i64, 1, 256},
        {&I::eventChild, kFracture, "child_id", i64, 1, 1024},
        {&I::dustTime, kDust, "time_s", d, 1, 256},
        {&I::dustParent, kDust, "parent_id", i64, 1, 256},
        {&I::dustVoxels, kDust, "voxel_count", i64, 1, 256},
        {&I::dustMassRows, kDust, "mass_kg", d, 1, 256},
        {&I::dustMomentum, kDust, "linear_momentum_kg_m_s", d, 3, 256},
    };
}

const char* const kGroupPaths[] = {"frames", "bodies", "events/fracture", "dust"};

}  // namespace

HistoryWriter::HistoryWriter(const std::string& path, const HistoryHeader& header) : mImpl(std::make_unique<Impl>())
{
    Impl& m = *mImpl;
    m.path = path;
    initialiseHdf5();
    m.file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (m.file < 0) throw IoError(path + ": cannot create the HDF5 history");
    try {
        writeStringAttribute(m.file, "format", kHistoryFormatName);
        writeScalarAttribute(m.file, "format_version", H5T_NATIVE_INT, kHistoryFormatVersion);
        writeScalarAttribute(m.file, "voxel_size_m", H5T_NATIVE_DOUBLE, header.voxelSizeM);
        writeScalarAttribute(m.file, "seed", H5T_NATIVE_UINT64, header.seed);
        writeStringAttribute(m.file, "scene_json", header.sceneJson);
        writeScalarAttribute(m.file, "run_complete", H5T_NATIVE_INT, 0);

        const hid_t frames = m.groups[0] = checkId(H5Gcreate2(m.file, "frames", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "frames");
        const hid_t bodies = m.groups[1] = checkId(H5Gcreate2(m.file, "bodies", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "bodies");
        const hid_t events = m.groups[2] = checkId(H5Gcreate2(m.file, "events", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "events");
        const hid_t fracture = m.groups[3] = checkId(H5Gcreate2(events, "fracture", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "fracture");
        const hid_t dust = m.groups[4] = checkId(H5Gcreate2(m.file, "dust", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "dust");
        const hid_t charges = m.groups[5] = checkId(H5Gcreate2(m.file, "charges", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "charges");
        const hid_t parents[] = {frames, bodies, fracture, dust};
        for (const SeriesSpec& spec : seriesSpecs()) m.*spec.member = Series(parents[spec.group], spec.name, spec.type, spec.cols, spec.chunkRows);
        const int64_t zero = 0;
        m.bodyOffset.append(&zero, 1);
        m.eventChildOffset.append(&zero, 1);

        const hid_t d = H5T_NATIVE_DOUBLE, i8 = H5T_NATIVE_INT8;
        Series chargePos(charges, "position_m", d, 3, 16), chargeMass(charges, "tnt_kg", d, 1, 16),
            chargeTime(charges, "detonation_time_s", d, 1, 16);
        Series chargeBurst(charges, "surface_burst", i8, 1, 16);
        for (const ChargeRow& c : header.charges) {
            chargePos.append(c.positionM.data(), 1);
            chargeMass.append(&c.tntKg, 1);
            chargeTime.append(&c.detonationTimeS, 1);
            const int8_t surface = c.burst == "surface";
            chargeBurst.append(&surface, 1);
        }
        for (Series* s : {&chargePos, &chargeMass, &chargeTime, &chargeBurst}) s->close();
        m.flush();
    } catch (...) {
        m.close();
        throw;
    }
}

HistoryWriter::HistoryWriter(const std::string& path, const HistoryResumePoint& resume) : mImpl(std::make_unique<Impl>())
{
    Impl& m = *mImpl;
    m.path = path;
    initialiseHdf5();
    m.file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    if (m.file < 0) throw IoError(path + ": cannot open the HDF5 history to continue it");
    try {
        hid_t parents[4];
        for (int g = 0; g < 4; ++g) parents[g] = m.groups[g] = checkId(H5Gopen2(m.file, kGroupPaths[g], H5P_DEFAULT), kGroupPaths[g]);
        // Rows each group keeps: what the checkpoint's frames, events and dust wrote.
        Series offsets = Series::open(parents[kFrames], "body_offset", H5T_NATIVE_INT64, 1, resume.frames + 1);
        m.bodyRows = offsets.int64At(resume.frames);
        offsets.close();
        Series childOffsets = Series::open(parents[kFracture], "child_offset", H5T_NATIVE_INT64, 1, resume.fractureEvents + 1);
        m.childRows = childOffsets.int64At(resume.fractureEvents);
        childOffsets.close();
        for (const SeriesSpec& spec : seriesSpecs()) {
            hsize_t rows = 0;
            switch (spec.group) {
            case kFrames: rows = resume.frames; break;
            case kBodies: rows = m.bodyRows; break;
            case kFracture: rows = resume.fractureEvents; break;
            case kDust: rows = resume.dustRecords; break;
            }
            if (spec.member == &Impl::bodyOffset || spec.member == &Impl::eventChildOffset) ++rows;
            if (spec.member == &Impl::eventChild) rows = m.childRows;
            m.*spec.member = Series::open(parents[spec.group], spec.name, spec.type, spec.cols, rows);
        }
        writeScalarAttribute(m.file, "run_complete", H5T_NATIVE_INT, 0);
        m.flush();
    } catch (...) {
        m.close();
        throw;
    }
}

HistoryWriter::~HistoryWriter()
{
    if (mImpl) mImpl->close();
}

void HistoryWriter::Impl::requireSpaceFor(size_t newBodyRows, const std::vector<FractureEvent>& events, size_t newDustRows) const
{
    // HDF5 cannot recover from running out of space part-way through a flush (the file is left
    // claiming more than it holds, and does not open), so refuse before touching it. The
    // margin covers a new chunk for every dataset and the metadata.
    size_t childCount = 0;
    for (const FractureEvent& e : events) childCount += e.childIds.size();
    const uintmax_t needed = newBodyRows * sizeof(BodyRow) + (events.size() + childCount + newDustRows) * 64 + (uintmax_t(512) << 10);
    const std::filesystem::path directory = std::filesystem::path(path).parent_path();
    std::error_code ec;
    const auto space = std::filesystem::space(directory.empty() ? "." : directory, ec);
    if (!ec && space.available < needed)
        throw IoError(path + ": disk full (" + std::to_string(space.available) + " bytes free, a frame needs about " +
                      std::to_string(needed) + "); the frames before it are intact");
}

void HistoryWriter::Impl::appendBodies(const std::vector<BodyRow>& bodies)
{
    const size_t n = bodies.size();
    std::vector<int64_t> ids(n), parents(n), voxelCounts(n);
    std::vector<double> pos(3 * n), ori(4 * n), lin(3 * n), ang(3 * n), masses(n);
    std::vector<int8_t> sleeping(n), anchoredFlags(n);
    for (size_t i = 0; i < n; ++i) {
        const BodyRow& b = bodies[i];
        ids[i] = b.id;
        parents[i] = b.parentId;
        voxelCounts[i] = b.voxelCount;
        masses[i] = b.massKg;
        sleeping[i] = b.asleep;
        anchoredFlags[i] = b.anchored;
        for (int k = 0; k < 3; ++k) {
            pos[3 * i + k] = b.positionM[k];
            lin[3 * i + k] = b.linearVelocityMS[k];
            ang[3 * i + k] = b.angularVelocityRadS[k];
        }
        for (int k = 0; k < 4; ++k) ori[4 * i + k] = b.orientationWxyz[k];
    }
    id.append(ids.data(), n);
    parent.append(parents.data(), n);
    position.append(pos.data(), n);
    orientation.append(ori.data(), n);
    linVel.append(lin.data(), n);
    angVel.append(ang.data(), n);
    mass.append(masses.data(), n);
    voxels.append(voxelCounts.data(), n);
    asleep.append(sleeping.data(), n);
    anchored.append(anchoredFlags.data(), n);
    bodyRows += static_cast<int64_t>(n);
}

void HistoryWriter::Impl::appendEvents(const std::vector<FractureEvent>& events, const std::vector<DustRecord>& dust)
{
    for (const FractureEvent& e : events) {
        eventTime.append(&e.timeS, 1);
        eventParent.append(&e.parentId, 1);
        eventChild.append(e.childIds.data(), e.childIds.size());
        childRows += static_cast<int64_t>(e.childIds.size());
        eventChildOffset.append(&childRows, 1);
    }
    for (const DustRecord& d : dust) {
        dustTime.append(&d.timeS, 1);
        dustParent.append(&d.parentId, 1);
        dustVoxels.append(&d.voxelCount, 1);
        dustMassRows.append(&d.massKg, 1);
        dustMomentum.append(d.linearMomentum.data(), 1);
    }
}

void HistoryWriter::Impl::appendFrameRow(const FrameRow& f)
{
    kinetic.append(&f.kineticEnergyJ, 1);
    linear.append(f.linearMomentum.data(), 1);
    angular.append(f.angularMomentum.data(), 1);
    broken.append(&f.brokenLinks, 1);
    steps.append(&f.steps, 1);
    minDt.append(&f.minDtS, 1);
    bodyCount.append(&f.bodyCount, 1);
    voxelCount.append(&f.voxelCount, 1);
    dustMass.append(&f.dustMassKg, 1);
    latticeParticleSteps.append(&f.latticeParticleSteps, 1);
    discardedVibration.append(&f.discardedVibrationJ, 1);
    bodyOffset.append(&bodyRows, 1);
    time.append(&f.timeS, 1);
}

void HistoryWriter::appendFrame(const FrameRow& f, const std::vector<BodyRow>& bodies, const std::vector<FractureEvent>& events,
                                const std::vector<DustRecord>& dust)
{
    mImpl->requireSpaceFor(bodies.size(), events, dust.size());
    mImpl->appendBodies(bodies);
    mImpl->appendEvents(events, dust);
    // The frame row goes last: a reader that sees frame f also sees all of its bodies.
    mImpl->appendFrameRow(f);
    mImpl->flush();
}

void HistoryWriter::finish()
{
    writeScalarAttribute(mImpl->file, "run_complete", H5T_NATIVE_INT, 1);
    mImpl->flush();
    mImpl->close();
}


namespace {

class Reader {
public:
    explicit Reader(const std::string& path) : mPath(path)
    {
        initialiseHdf5();
        if (H5Fis_hdf5(path.c_str()) <= 0) throw IoError(path + ": not an HDF5 file (or missing)");
        mFile = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
        if (mFile < 0) throw IoError(path + ": cannot open");
    }
    ~Reader()
    {
        if (mFile >= 0) H5Fclose(mFile);
    }
    template <typename T>
    std::vector<T> read(const char* name, hid_t type, size_t cols = 1)
    {
        const hid_t d = H5Dopen2(mFile, name, H5P_DEFAULT);
        if (d < 0) throw IoError(mPath + ": missing dataset " + name + " (not a spall history?)");
        const hid_t space = H5Dget_space(d);
        hsize_t dims[2] = {0, 1};
        H5Sget_simple_extent_dims(space, dims, nullptr);
        std::vector<T> out(dims[0] * cols);
        if (!out.empty() && H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0) {
            H5Sclose(space);
            H5Dclose(d);
            throw IoError(mPath + ": cannot read " + name);
        }
        H5Sclose(space);
        H5Dclose(d);
        return out;
    }
    std::vector<Eigen::Vector3d> readVec3(const char* name)
    {
        const std::vector<double> flat = read<double>(name, H5T_NATIVE_DOUBLE, 3);
        std::vector<Eigen::Vector3d> out(flat.size() / 3);
        for (size_t i = 0; i < out.size(); ++i) out[i] = Eigen::Vector3d(flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]);
        return out;
    }
    template <typename T>
    T attribute(const char* name, hid_t type)
    {
        T value{};
        const hid_t a = H5Aopen(mFile, name, H5P_DEFAULT);
        if (a < 0 || H5Aread(a, type, &value) < 0) throw IoError(mPath + ": missing attribute " + name + " (not a spall history?)");
        H5Aclose(a);
        return value;
    }

private:
    std::string mPath;
    hid_t mFile = -1;
};

}  // namespace

History readHistory(const std::string& path)
{
    Reader r(path);
    History h;
    h.formatVersion = r.attribute<int>("format_version", H5T_NATIVE_INT);
    if (h.formatVersion != kHistoryFormatVersion)
        throw IoError(path + ": history format version " + std::to_string(h.formatVersion) + " is not the supported " +
                      std::to_string(kHistoryFormatVersion));
    h.runComplete = r.attribute<int>("run_complete", H5T_NATIVE_INT) != 0;
    h.voxelSizeM = r.attribute<double>("voxel_size_m", H5T_NATIVE_DOUBLE);
    h.seed = r.attribute<uint64_t>("seed", H5T_NATIVE_UINT64);
    const hid_t d = H5T_NATIVE_DOUBLE, i64 = H5T_NATIVE_INT64, i8 = H5T_NATIVE_INT8;
    h.timeS = r.read<double>("/frames/time_s", d);
    h.kineticEnergyJ = r.read<double>("/frames/kinetic_energy_J", d);
    h.minDtS = r.read<double>("/frames/min_dt_s", d);
    h.dustMassKg = r.read<double>("/frames/dust_mass_kg", d);
    h.discardedVibrationJ = r.read<double>("/frames/discarded_vibration_J", d);
    h.latticeParticleSteps = r.read<int64_t>("/frames/lattice_particle_steps", i64);
    h.bodyOffset = r.read<int64_t>("/frames/body_offset", i64);
    h.brokenLinks = r.read<int64_t>("/frames/broken_links", i64);
    h.steps = r.read<int64_t>("/frames/steps", i64);
    h.bodyCount = r.read<int64_t>("/frames/body_count", i64);
    h.voxelCount = r.read<int64_t>("/frames/voxel_count", i64);
    h.linearMomentum = r.readVec3("/frames/linear_momentum_kg_m_s");
    h.angularMomentum = r.readVec3("/frames/angular_momentum_kg_m2_s");
    h.bodyId = r.read<int64_t>("/bodies/id", i64);
    h.bodyParentId = r.read<int64_t>("/bodies/parent_id", i64);
    h.bodyVoxelCount = r.read<int64_t>("/bodies/voxel_count", i64);
    h.bodyMassKg = r.read<double>("/bodies/mass_kg", d);
    h.bodyPositionM = r.readVec3("/bodies/position_m");
    h.bodyLinearVelocityMS = r.readVec3("/bodies/linear_velocity_m_s");
    h.bodyAsleep = r.read<int8_t>("/bodies/asleep", i8);
    h.bodyAnchored = r.read<int8_t>("/bodies/anchored", i8);
    h.eventTimeS = r.read<double>("/events/fracture/time_s", d);
    h.eventParentId = r.read<int64_t>("/events/fracture/parent_id", i64);
    h.eventChildOffset = r.read<int64_t>("/events/fracture/child_offset", i64);
    h.chargePositionM = r.readVec3("/charges/position_m");
    h.chargeTntKg = r.read<double>("/charges/tnt_kg", d);
    // A run killed mid-frame may hold body rows past the last complete frame: keep what the
    // frame rows describe.
    const size_t frames = std::min(h.timeS.size(), h.bodyOffset.size() - 1);
    h.timeS.resize(frames);
    return h;
}

}  // namespace spall
