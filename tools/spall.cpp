// spall: command-line front end. Each subcommand is in a file of its own (Commands.h); this is
// the only place that turns library errors into exit codes.
#include "BenchAccuracy.h"
#include "BenchCollisions.h"
#include "Commands.h"

#include <spall/core/Error.h>
#include <spall/voxel/Voxelise.h>

#include <atomic>
#include <csignal>
#include <ctime>
#include <iostream>
#include <memory>

#include <unistd.h>

namespace {

std::atomic<bool> gStopRequested{false};
std::atomic<int64_t> gStopRequestedAtNs{0};  ///< CLOCK_MONOTONIC
static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<int64_t>::is_always_lock_free,
              "a signal handler may touch only lock-free atomics");

int64_t monotonicNs()
{
    timespec now{};
    ::clock_gettime(CLOCK_MONOTONIC, &now);  // async-signal-safe (POSIX)
    return int64_t(now.tv_sec) * 1000000000 + now.tv_nsec;
}

/// Says at once that the stop is heard (write(2) is async-signal-safe where stdio is not; the
/// flag is a lock-free atomic), once however often it is asked.
extern "C" void requestStop(int)
{
    if (gStopRequested.exchange(true)) return;
    gStopRequestedAtNs.store(monotonicNs());
    static const char kHeard[] = "\nspall: stopping: the current step finishes (or is given up after 2 s) and what is written stays readable\n";
    [[maybe_unused]] const ssize_t written = ::write(STDERR_FILENO, kHeard, sizeof kHeard - 1);
}

}  // namespace

void stopOnSignals()
{
    std::signal(SIGINT, requestStop);
    std::signal(SIGTERM, requestStop);
}

bool stopRequested() { return gStopRequested.load(); }

bool stopRequestedLongerThan(double seconds) { return gStopRequested.load() && double(monotonicNs() - gStopRequestedAtNs.load()) > 1e9 * seconds; }

void addBenchCommands(CLI::App& app, CommandAction& action)
{
    auto* bench = app.add_subcommand("bench", "Benchmarks that print tables (the micro-benchmarks are in spall_bench)");
    bench->require_subcommand(1);
    struct Options {
        bool json = false;
        long maxBoundaryVoxels = 1'000'000;
        std::string accuracyOutput = "accuracy";
        double sceneDurationS = 0.5;
    };
    auto o = std::make_shared<Options>();
    auto* collisions = bench->add_subcommand("collisions", "Table 5-1: steps per second against boundary voxels, per method");
    collisions->add_flag("--json", o->json, "One JSON row per method and size");
    collisions->add_option("--max-boundary-voxels", o->maxBoundaryVoxels, "Largest size to run")->check(CLI::PositiveNumber);
    collisions->callback([o, &action] { action = [o] { return spall::benchCollisions(o->json, o->maxBoundaryVoxels); }; });
    auto* accuracy = bench->add_subcommand("accuracy", "Error against a reference next to run time: CSV and log-log plots");
    accuracy->add_option("-o,--output", o->accuracyOutput, "Directory for accuracy.csv and the plots");
    accuracy->add_option("--scene-duration", o->sceneDurationS, "Seconds of the default scene per variant (s)")->check(CLI::PositiveNumber);
    accuracy->callback([o, &action] { action = [o] { return spall::benchAccuracy(o->accuracyOutput, o->sceneDurationS); }; });
}

int main(int argc, char** argv)
{
    CLI::App app{"spall: volumetric debris from a physically based blast"};
    app.set_version_flag("--version", "spall " SPALL_VERSION);
    app.require_subcommand(1);
    CommandAction action;
    addVoxeliseCommand(app, action);
    addBlastCommand(app, action);
    addRunCommand(app, action);
    addRenderCommand(app, action);
    addInspectCommand(app, action);
    addBenchCommands(app, action);
    addExportCommand(app, action);
    addViewCommand(app, action);
    addDebrisCommand(app, action);
    addLoadsCommand(app, action);
    addSweepCommands(app, action);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    try {
        return action ? action() : 0;
    } catch (const spall::InputError& e) {
        std::cerr << "spall: error: " << e.what() << "\n";
        return 2;
    } catch (const spall::VoxeliseInterrupted& e) {
        std::cerr << "\nspall: stopped: " << e.what() << "\n";
        return 130;  // 128 + SIGINT, as a shell reports a command Ctrl-C stopped

    } catch (const std::exception& e) {
        std::cerr << "spall: error: " << e.what() << "\n";
        return 1;
    }
}
