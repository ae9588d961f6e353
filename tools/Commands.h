// The subcommands of `spall`, one file each. Each registers its subcommand, options and all, on
// the application; when the command line chooses it, `action` becomes the call that runs it,
// which returns the exit code and throws spall's errors (tools/spall.cpp turns those into codes).
#pragma once

#include <spall/core/EnumNames.h>
#include <spall/core/Error.h>
#include <spall/output/GltfExport.h>

#include <CLI/CLI.hpp>

#include <functional>

using CommandAction = std::function<int()>;

/// Ctrl-C and SIGTERM set a flag that long commands poll, so they stop where what they wrote
/// stays readable instead of dying mid-write.
void stopOnSignals();
bool stopRequested();
bool stopRequestedLongerThan(double seconds);

/// The library's interrupter for the same flag: a step still running this long after the
/// request is given up (a step of a large lattice can take a minute; the run then goes on from
/// its last checkpoint when resumed).
struct StopRequest : spall::Interrupter {
    static constexpr double kStepGraceS = 2.0;
    bool wasInterrupted(int) override { return stopRequested(); }
    bool mustAbandonStep() override { return stopRequestedLongerThan(kStepGraceS); }
};

/// An enum-valued option; a bad value is an error naming the option.
template <typename E>
E parseOption(const std::string& option, const std::string& value)
{
    try {
        return spall::parseEnum<E>(value);
    } catch (const spall::InputError& e) {
        throw spall::InputError(option + ": " + e.what());
    }
}

void addVoxeliseCommand(CLI::App& app, CommandAction& action);
void addBlastCommand(CLI::App& app, CommandAction& action);
void addRunCommand(CLI::App& app, CommandAction& action);
void addRenderCommand(CLI::App& app, CommandAction& action);
void addInspectCommand(CLI::App& app, CommandAction& action);
void addBenchCommands(CLI::App& app, CommandAction& action);
void addExportCommand(CLI::App& app, CommandAction& action);
void addViewCommand(CLI::App& app, CommandAction& action);
void addDebrisCommand(CLI::App& app, CommandAction& action);
void addLoadsCommand(CLI::App& app, CommandAction& action);
void addSweepCommands(CLI::App& app, CommandAction& action);

/// `spall export gltf`: writes GLBPATH (default OUTDIR/debris.glb) from OUTDIR's frames.
int exportGltfCommand(const std::string& outDir, std::string glbPath, bool quiet);
/// OUTDIR/debris.glb, where `spall export gltf OUTDIR` and `spall run --gltf` write it.
std::string defaultGlbPath(const std::string& outDir);
/// The export's progress on stderr (nothing when quiet), and its one-line report.
std::function<void(int, int)> gltfProgress(bool quiet);
void printGltfReport(const std::string& glbPath, const spall::GltfExportReport& report);
