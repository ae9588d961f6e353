// `spall voxelise`: a mesh or a primitive into a solid .vdb body.
#include "Commands.h"

#include <memory>

#include <spall/core/Error.h>
#include <spall/voxel/VdbIo.h>
#include <spall/voxel/Voxelise.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <sstream>

namespace {

/// Percent progress on stderr, at most a few updates per second; stops on Ctrl-C or SIGTERM.
class ProgressPrinter : public spall::Interrupter {
public:
    ProgressPrinter(std::string label, bool quiet) : mLabel(std::move(label)), mQuiet(quiet) {}
    ~ProgressPrinter() override
    {
        if (mPrinted) std::fprintf(stderr, "\r%s done\n", mLabel.c_str());
    }
    bool wasInterrupted(int percent) override
    {
        const auto now = std::chrono::steady_clock::now();
        const bool due = !mPrinted || now - mLast >= std::chrono::milliseconds(250) || percent >= 100;
        if (!mQuiet && percent >= 0 && due) {
            mLast = now;
            mPrinted = true;
            std::fprintf(stderr, "\r%s %3d%%", mLabel.c_str(), percent);
        }
        return stopRequested();
    }

private:
    std::string mLabel;
    bool mQuiet;
    bool mPrinted = false;
    std::chrono::steady_clock::time_point mLast;
};

spall::Primitive parsePrimitive(const std::string& spec)
{
    // box:X,Y,Z | sphere:R | cylinder:R,H (metres)
    const auto colon = spec.find(':');
    const std::string kind = spec.substr(0, colon);
    std::vector<double> v;
    if (colon != std::string::npos) {
        std::stringstream ss(spec.substr(colon + 1));
        std::string item;
        while (std::getline(ss, item, ',')) {
            try {
                v.push_back(std::stod(item));
            } catch (const std::exception&) {
                throw spall::InputError("primitive '" + spec + "': '" + item + "' is not a number");
            }
        }
    }
    spall::Primitive p;
    if (kind == "box" && v.size() == 3) {
        p.shape = spall::PrimitiveShape::Box;
        p.sizeM = {v[0], v[1], v[2]};
    } else if (kind == "sphere" && v.size() == 1) {
        p.shape = spall::PrimitiveShape::Sphere;
        p.sizeM = {v[0], v[0], v[0]};
    } else if (kind == "cylinder" && v.size() == 2) {
        p.shape = spall::PrimitiveShape::Cylinder;
        p.sizeM = {v[0], v[0], v[1]};
    } else {
        throw spall::InputError("primitive '" + spec + "' is not box:X,Y,Z, sphere:R or cylinder:R,H (metres)");
    }
    return p;
}


int runVoxelise(const std::string& input, const std::string& primitiveSpec, const std::string& output,
                const spall::VoxeliseSettings& settings, bool quiet)
{
    const double voxelSize = settings.voxelSizeM;
    spall::VoxeliseResult result;
    std::string source;
    const auto start = std::chrono::steady_clock::now();
    if (!primitiveSpec.empty()) {
        source = primitiveSpec;
        result = spall::voxelisePrimitive(parsePrimitive(primitiveSpec), settings);
    } else {
        source = input;
        std::vector<std::string> notes;
        const spall::TriangleMesh mesh = spall::loadMesh(input, &notes);
        stopOnSignals();
        try {
            ProgressPrinter progress("voxelising " + input, quiet);
            result = spall::voxeliseMesh(mesh, settings, input, &progress);
        } catch (const spall::VoxeliseInterrupted& e) {
            throw spall::VoxeliseInterrupted(std::string(e.what()) + "; nothing was written");
        }
        result.notes.insert(result.notes.begin(), notes.begin(), notes.end());
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    // The file places each voxel where it lies in the mesh's (or primitive's) own frame.
    openvdb::math::Transform::Ptr placed = openvdb::math::Transform::createLinearTransform(voxelSize);
    placed->postTranslate(openvdb::Vec3d(result.localOffsetM.x(), result.localOffsetM.y(), result.localOffsetM.z()));
    result.grid->setTransform(placed);
    spall::writeVoxelisedBody(output, *result.grid, voxelSize, source);

    const spall::MassProperties mp = spall::computeMassProperties(*result.grid, voxelSize, 1000.0);
    const openvdb::CoordBBox box = result.grid->evalActiveVoxelBoundingBox();
    for (const auto& note : result.notes) std::cerr << "spall voxelise: note: " << source << ": " << note << "\n";
    std::cout << "voxelised " << source << " at " << voxelSize << " m\n"
              << "  voxels:        " << result.voxelCount << "\n"
              << "  links:         " << spall::countLinks(*result.grid) << "\n"
              << "  volume:        " << mp.voxelCount * voxelSize * voxelSize * voxelSize << " m^3"
              << (result.enclosedVolumeM3 > 0 ? " (the mesh encloses " + std::to_string(result.enclosedVolumeM3) + " m^3)" : "") << "\n"
              << "  extent:        " << box.dim().x() * voxelSize << " x " << box.dim().y() * voxelSize << " x "
              << box.dim().z() * voxelSize << " m\n"
              << "  throughput:    " << (seconds > 0 ? result.voxelCount / seconds : 0.0) << " voxels/s\n"
              << "  written:       " << output << "\n";
    return 0;
}

}  // namespace

void addVoxeliseCommand(CLI::App& app, CommandAction& action)
{
    struct Options {
        std::string input, primitive, output;
        spall::VoxeliseSettings settings;
        std::string inside = "auto";
        bool quiet = false;
    };
    auto o = std::make_shared<Options>();
    auto* sub = app.add_subcommand("voxelise", "Voxelise a mesh or a primitive into a solid .vdb body");
    sub->alias("voxelize");
    sub->add_option("input", o->input, "Mesh file (OBJ, STL, PLY, OFF, glTF, ...)");
    sub->add_option("--primitive", o->primitive, "Instead of a mesh: box:X,Y,Z | sphere:R | cylinder:R,H (m)");
    sub->add_option("-o,--output", o->output, "Output .vdb")->required();
    sub->add_option("--voxel-size", o->settings.voxelSizeM, "Voxel edge (m)")->required();
    sub->add_option("--max-voxels", o->settings.maxVoxels, "Refuse results with more voxels than this");
    sub->add_option("--inside", o->inside,
                    "How a mesh's inside is found: auto (level set if watertight, else winding number), level-set, winding-number");
    sub->add_option("--shell-thickness", o->settings.shellThicknessM,
                    "Instead of the inside, a shell this thick around the surface, for a sheet or a terrain patch (m)")
        ->check(CLI::NonNegativeNumber);
    sub->add_flag("--quiet", o->quiet, "No progress on stderr");
    sub->callback([o, &action] {
        action = [o] {
            if (o->input.empty() == o->primitive.empty()) throw spall::InputError("give either a mesh file or --primitive, not both or neither");
            o->settings.insideTest = parseOption<spall::InsideTest>("--inside", o->inside);
            return runVoxelise(o->input, o->primitive, o->output, o->settings, o->quiet);
        };
    });
}
