#include <spall/output/History.h>

#include "HistorySeries.h"

#include <spall/output/H5Out.h>

#include <spall/core/Error.h>

#include <hdf5.h>

#include <cstring>
#include <filesystem>
#include <string>
#include <variant>

namespace spall {

using history::check;
using history::checkId;
using history::Series;
using history::writeScalarAttribute;
using history::writeStringAttribute;

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
    void close();
};

namespace {

enum Group { kFrames, kBodies, kFracture, kDust };

/// Where readHistory puts a dataset (nothing: it is written for notebooks only).
using HistoryField = std::variant<std::monostate, std::vector<double> History::*, std::vector<int64_t> History::*,
                                  std::vector<int8_t> History::*, std::vector<Eigen::Vector3d> History::*>;
constexpr std::monostate kNotRead{};

/// Every growing dataset of the history: where it lives, its type and shape, and where the reader
/// puts it. The one list the writer creates and appends by and the reader reads by.
struct SeriesSpec {
    Series HistoryWriter::Impl::*member;
    Group group;
    const char* name;
    hid_t type;
    hsize_t cols;
    hsize_t chunkRows;
    HistoryField readInto;
};

std::vector<SeriesSpec> seriesSpecs()
{
    using I = HistoryWriter::Impl;
    const hid_t d = H5T_NATIVE_DOUBLE, i64 = H5T_NATIVE_INT64, i8 = H5T_NATIVE_INT8;
    return {
        {&I::time, kFrames, "time_s", d, 1, 256, &History::timeS},
        {&I::bodyOffset, kFrames, "body_offset", i64, 1, 256, &History::bodyOffset},
        {&I::kinetic, kFrames, "kinetic_energy_J", d, 1, 256, &History::kineticEnergyJ},
        {&I::linear, kFrames, "linear_momentum_kg_m_s", d, 3, 256, &History::linearMomentum},
        {&I::angular, kFrames, "angular_momentum_kg_m2_s", d, 3, 256, &History::angularMomentum},
        {&I::broken, kFrames, "broken_links", i64, 1, 256, &History::brokenLinks},
        {&I::steps, kFrames, "steps", i64, 1, 256, &History::steps},
        {&I::minDt, kFrames, "min_dt_s", d, 1, 256, &History::minDtS},
        {&I::bodyCount, kFrames, "body_count", i64, 1, 256, &History::bodyCount},
        {&I::voxelCount, kFrames, "voxel_count", i64, 1, 256, &History::voxelCount},
        {&I::dustMass, kFrames, "dust_mass_kg", d, 1, 256, &History::dustMassKg},
        {&I::latticeParticleSteps, kFrames, "lattice_particle_steps", i64, 1, 256, &History::latticeParticleSteps},
        {&I::discardedVibration, kFrames, "discarded_vibration_J", d, 1, 256, &History::discardedVibrationJ},
        {&I::id, kBodies, "id", i64, 1, 1024, &History::bodyId},
        {&I::parent, kBodies, "parent_id", i64, 1, 1024, &History::bodyParentId},
        {&I::position, kBodies, "position_m", d, 3, 1024, &History::bodyPositionM},
        {&I::orientation, kBodies, "orientation_wxyz", d, 4, 1024, kNotRead},
        {&I::linVel, kBodies, "linear_velocity_m_s", d, 3, 1024, &History::bodyLinearVelocityMS},
        {&I::angVel, kBodies, "angular_velocity_rad_s", d, 3, 1024, kNotRead},
        {&I::mass, kBodies, "mass_kg", d, 1, 1024, &History::bodyMassKg},
        {&I::voxels, kBodies, "voxel_count", i64, 1, 1024, &History::bodyVoxelCount},
        {&I::asleep, kBodies, "asleep", i8, 1, 1024, &History::bodyAsleep},
        {&I::anchored, kBodies, "anchored", i8, 1, 1024, &History::bodyAnchored},
        {&I::eventTime, kFracture, "time_s", d, 1, 256, &History::eventTimeS},
        {&I::eventParent, kFracture, "parent_id", i64, 1, 256, &History::eventParentId},
        {&I::eventChildOffset, kFracture, "child_offset", i64, 1, 256, &History::eventChildOffset},
        {&I::eventChild, kFracture, "child_id", i64, 1, 1024, kNotRead},
        {&I::dustTime, kDust, "time_s", d, 1, 256, kNotRead},
        {&I::dustParent, kDust, "parent_id", i64, 1, 256, kNotRead},
        {&I::dustVoxels, kDust, "voxel_count", i64, 1, 256, kNotRead},
        {&I::dustMassRows, kDust, "mass_kg", d, 1, 256, kNotRead},
        {&I::dustMomentum, kDust, "linear_momentum_kg_m_s", d, 3, 256, kNotRead},
    };
}

const char* const kGroupPaths[] = {"frames", "bodies", "events/fracture", "dust"};

}  // namespace

void HistoryWriter::Impl::close()
{
    for (const SeriesSpec& spec : seriesSpecs()) (this->*spec.member).close();
    for (hid_t& g : groups)
        if (g >= 0) H5Gclose(g), g = -1;
    if (file >= 0) H5Fclose(file);
    file = -1;
}

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

void readSeries(Reader&, const std::string&, hid_t, History&, std::monostate) {}

template <typename T>
void readSeries(Reader& r, const std::string& name, hid_t type, History& h, std::vector<T> History::*field)
{
    h.*field = r.read<T>(name.c_str(), type);
}

void readSeries(Reader& r, const std::string& name, hid_t, History& h, std::vector<Eigen::Vector3d> History::*field)
{
    h.*field = r.readVec3(name.c_str());
}

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
    for (const SeriesSpec& spec : seriesSpecs()) {
        const std::string name = std::string("/") + kGroupPaths[spec.group] + "/" + spec.name;
        std::visit([&](auto field) { readSeries(r, name, spec.type, h, field); }, spec.readInto);
    }
    h.chargePositionM = r.readVec3("/charges/position_m");
    h.chargeTntKg = r.read<double>("/charges/tnt_kg", H5T_NATIVE_DOUBLE);
    // A run killed mid-frame may hold body rows past the last complete frame: keep what the
    // frame rows describe.
    const size_t frames = std::min(h.timeS.size(), h.bodyOffset.size() - 1);
    h.timeS.resize(frames);
    return h;
}

}  // namespace spall
