// `spall sweep`: one scene over seeds and key values, each variant run by `spall sweep-task`
// in local processes or as a Slurm job array, then one summary (docs/sweeps.md).
#include "Commands.h"

#include <spall/sweep/Sweep.h>

#include <tbb/global_control.h>

#include <chrono>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <thread>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace fs = std::filesystem;

namespace {

struct SweepOptions {
    std::string scenePath, outDir, collectDir;
    int seeds = 0;
    std::vector<std::string> vary;
    std::string scheduler = "local";
    int jobs = 1;
    std::string partition, account, timeLimit;
    int cpusPerTask = 1;
};

std::string selfExecutable() { return fs::read_symlink("/proc/self/exe").string(); }

int summarise(const std::string& dir, const spall::SweepPlan& plan)
{
    const spall::SweepSummary summary = spall::collectSweep(dir, plan);
    spall::writeSweepSummary(dir, plan, summary);
    int unfinished = 0;
    for (const spall::SweepVariant& v : plan.variants) {
        const spall::VariantStatus& st = summary.status[v.index];
        const spall::VariantFigures& f = summary.figures[v.index];
        if (st.state == spall::VariantState::Done)
            std::printf("%s seed %llu %s: %lld fragments, %lld hazardous, max throw %.2f m, hazardous fragment distance %.2f m\n",
                        v.name().c_str(), static_cast<unsigned long long>(v.seed), v.overridesText().c_str(), static_cast<long long>(f.fragments),
                        static_cast<long long>(f.hazardous), f.maxThrowDistanceM, f.hazardousFragmentDistanceM);
        else {
            ++unfinished;
            std::printf("%s seed %llu %s: %s %s\n", v.name().c_str(), static_cast<unsigned long long>(v.seed), v.overridesText().c_str(),
                        spall::enumName(st.state).c_str(), st.message.c_str());
        }
    }
    for (const auto& group : summary.groups) {
        std::vector<double> hfd;
        for (int i : group)
            if (summary.status[i].state == spall::VariantState::Done) hfd.push_back(summary.figures[i].hazardousFragmentDistanceM);
        const spall::MeanInterval m = spall::meanInterval(hfd);
        const std::string overrides = plan.variants[group.front()].overridesText();
        if (!spall::seedsChangedAnything(summary, group))
            std::printf("group %s: hazardous fragment distance %.2f m, every figure the same for all %lld seeds: nothing in this scene "
                        "draws on the seed (no material scatters), so they say nothing about spread\n",
                        overrides.c_str(), m.mean, static_cast<long long>(m.n));
        else
            std::printf("group %s: hazardous fragment distance %.2f m +- %.2f m (95 %%, %lld seeds; %.2f to %.2f m)\n", overrides.c_str(), m.mean,
                        m.halfWidth, static_cast<long long>(m.n), m.min, m.max);
    }
    std::printf("summary: %s/summary.csv, summary_groups.csv, summary.h5, summary_hfd.png\n", dir.c_str());
    if (unfinished) std::fprintf(stderr, "spall sweep: %d of %zu variants failed or did not finish (see above and %s/logs)\n", unfinished, plan.variants.size(), dir.c_str());
    return unfinished ? 1 : 0;
}

/// The plan in DIR: a new one, or the same one again (a re-run resumes it); another is an error.
spall::SweepPlan preparePlan(const SweepOptions& o, const std::string& dir)
{
    std::vector<spall::SweepAxis> axes;
    for (const std::string& text : o.vary) axes.push_back(spall::parseSweepAxis(text));
    if (axes.empty() && o.seeds == 0) throw spall::InputError("spall sweep: give --seeds N or --vary KEY=V1,V2,... (or both)");
    spall::SweepPlan plan = spall::planSweep(o.scenePath, axes, o.seeds);
    if (fs::exists(dir + "/sweep.json")) {
        if (!spall::samePlan(spall::readSweepPlan(dir), plan))
            throw spall::InputError(dir + "/sweep.json: the directory holds a different sweep; choose another -o");
        return plan;
    }
    fs::create_directories(dir + "/logs");
    spall::writeSweepPlan(dir, plan);
    return plan;
}

std::vector<int> unfinishedVariants(const std::string& dir, const spall::SweepPlan& plan)
{
    std::vector<int> indices;
    for (const spall::SweepVariant& v : plan.variants)
        if (spall::readVariantStatus(dir, v).state != spall::VariantState::Done) indices.push_back(v.index);
    return indices;
}

pid_t startTask(const std::string& dir, int index, int threads)
{
    const std::string exe = selfExecutable(), log = dir + "/logs/task-" + std::to_string(index) + ".log";
    posix_spawn_file_actions_t files;
    posix_spawn_file_actions_init(&files);
    posix_spawn_file_actions_addopen(&files, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&files, STDOUT_FILENO, STDERR_FILENO);
    const std::vector<std::string> args = {exe, "sweep-task", dir, "--index", std::to_string(index), "--threads", std::to_string(threads)};
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    pid_t pid = 0;
    const int error = posix_spawn(&pid, exe.c_str(), &files, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&files);
    if (error) throw spall::IoError("cannot start " + exe + " sweep-task: " + std::strerror(error));
    return pid;
}

/// Runs the tasks with at most `jobs` at a time; a stop request is passed on to the running
/// tasks (each stops between two steps with a checkpoint) and starts no more.
void runLocally(const std::string& dir, const spall::SweepPlan& plan, const std::vector<int>& indices, int jobs)
{
    const int threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()) / jobs);
    std::map<pid_t, int> running;
    size_t next = 0, finished = 0;
    bool stopping = false;
    while (next < indices.size() || !running.empty()) {
        while (!stopping && next < indices.size() && static_cast<int>(running.size()) < jobs) {
            running[startTask(dir, indices[next], threads)] = indices[next];
            ++next;
        }
        if (stopRequested() && !stopping) {
            stopping = true;
            for (const auto& [pid, index] : running) kill(pid, SIGTERM);
        }
        const pid_t done = waitpid(-1, nullptr, WNOHANG);
        if (done <= 0) {
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
            continue;
        }
        const int index = running[done];
        running.erase(done);
        const spall::SweepVariant& variant = plan.variants[index];
        std::printf("%s %s (%zu of %zu)\n", variant.name().c_str(), spall::enumName(spall::readVariantStatus(dir, variant).state).c_str(), ++finished,
                    indices.size());
        std::fflush(stdout);
        if (stopping && next < indices.size() && running.empty()) break;
    }
}

std::string runCapturing(const std::string& command)
{
    FILE* pipe = popen((command + " 2>&1").c_str(), "r");
    if (!pipe) throw spall::IoError("cannot run " + command);
    std::string out;
    char buffer[512];
    while (fgets(buffer, sizeof buffer, pipe)) out += buffer;
    if (pclose(pipe) != 0) throw spall::IoError(command + " failed: " + out);
    while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
    return out;
}

std::string quoted(const std::string& s) { return "'" + s + "'"; }

std::string slurmOptions(const SweepOptions& o)
{
    std::string options;
    if (!o.partition.empty()) options += " --partition=" + quoted(o.partition);
    if (!o.account.empty()) options += " --account=" + quoted(o.account);
    if (!o.timeLimit.empty()) options += " --time=" + quoted(o.timeLimit);
    return options;
}

/// One job array of the unfinished variants (at most `jobs` at once), then a job that builds the
/// summary once the array has ended, however it ended.
int submitToSlurm(const SweepOptions& o, const std::string& dir, const std::vector<int>& indices)
{
    std::string list;
    for (int i : indices) list += (list.empty() ? "" : ",") + std::to_string(i);
    const std::string script = dir + "/sweep.sbatch";
    std::ofstream(script) << "#!/bin/bash\n#SBATCH --job-name=spall-sweep\n#SBATCH --array=" << list << "%" << o.jobs << "\n#SBATCH --output="
                          << dir << "/logs/task-%a.log\n#SBATCH --cpus-per-task=" << o.cpusPerTask << "\n"
                          << "exec " << quoted(selfExecutable()) << " sweep-task " << quoted(dir) << " --threads " << o.cpusPerTask << "\n";
    const std::string array = runCapturing("sbatch --parsable" + slurmOptions(o) + " " + quoted(script));
    const std::string collect = runCapturing("sbatch --parsable --job-name=spall-sweep-collect --dependency=afterany:" + array +
                                             slurmOptions(o) + " --output=" + quoted(dir + "/logs/collect.log") + " --wrap " +
                                             quoted("exec '" + selfExecutable() + "' sweep --collect '" + dir + "'"));
    std::printf("submitted job array %s (%zu variants, at most %d at once) and summary job %s; the summary appears in %s/summary.csv\n",
                array.c_str(), indices.size(), o.jobs, collect.c_str(), dir.c_str());
    return 0;
}

int sweepCommand(const SweepOptions& o)
{
    if (!o.collectDir.empty()) {
        const std::string dir = fs::absolute(o.collectDir).lexically_normal().string();
        return summarise(dir, spall::readSweepPlan(dir));
    }
    if (o.scenePath.empty() || o.outDir.empty()) throw spall::InputError("spall sweep: give SCENE and -o DIR (or --collect DIR)");
    const std::string dir = fs::absolute(o.outDir).lexically_normal().string();
    const spall::SweepPlan plan = preparePlan(o, dir);
    const std::vector<int> todo = unfinishedVariants(dir, plan);
    std::printf("sweep %s: %zu variants, %zu to run (%s)\n", dir.c_str(), plan.variants.size(), todo.size(), o.scheduler.c_str());
    if (o.scheduler == "slurm" && !todo.empty()) return submitToSlurm(o, dir, todo);
    stopOnSignals();
    runLocally(dir, plan, todo, o.jobs);
    const int code = summarise(dir, plan);
    return stopRequested() ? 130 : code;
}

int sweepTaskCommand(const std::string& dir, int index, int threads)
{
    if (index < 0) {
        const char* task = std::getenv("SLURM_ARRAY_TASK_ID");
        if (!task) throw spall::InputError("spall sweep-task: give --index or run it as a Slurm array task (SLURM_ARRAY_TASK_ID)");
        index = std::atoi(task);
    }
    tbb::global_control threadLimit(tbb::global_control::max_allowed_parallelism, std::max(1, threads));
    stopOnSignals();
    StopRequest stop;
    const spall::SweepPlan plan = spall::readSweepPlan(dir);
    const spall::VariantState state = spall::runSweepVariant(dir, plan, index, &stop);
    const spall::VariantStatus status = spall::readVariantStatus(dir, plan.variants.at(index));
    std::printf("%s: %s %s\n", plan.variants[index].name().c_str(), spall::enumName(state).c_str(), status.message.c_str());
    return state == spall::VariantState::Done ? 0 : state == spall::VariantState::Stopped ? 130 : 1;
}

}  // namespace

void addSweepCommands(CLI::App& app, CommandAction& action)
{
    auto o = std::make_shared<SweepOptions>();
    auto* sweep = app.add_subcommand("sweep", "One scene over seeds and key values, run locally or on Slurm, with a summary of the debris");
    sweep->add_option("scene", o->scenePath, "The scene (JSON)");
    sweep->add_option("-o,--output", o->outDir, "The sweep's directory (sweep.json, variants/, logs/, summary.*)");
    sweep->add_option("--seeds", o->seeds, "Seeds per variant: the scene's seed + 0 ... N-1")->check(CLI::Range(1, 100000));
    sweep->add_option("--vary", o->vary, "KEY=V1,V2,...: a scene key path (charges[0].tnt_kg) and its values; repeat for more keys");
    sweep->add_option("--scheduler", o->scheduler, "local (processes here) or slurm (a job array)")->check(CLI::IsMember({"local", "slurm"}))->capture_default_str();
    sweep->add_option("--jobs", o->jobs, "Variants at once")->check(CLI::Range(1, 10000))->capture_default_str();
    sweep->add_option("--partition", o->partition, "Slurm partition");
    sweep->add_option("--account", o->account, "Slurm account");
    sweep->add_option("--time-limit", o->timeLimit, "Slurm time limit per variant (e.g. 2:00:00)");
    sweep->add_option("--cpus-per-task", o->cpusPerTask, "Slurm CPUs per variant")->check(CLI::Range(1, 1024))->capture_default_str();
    sweep->add_option("--collect", o->collectDir, "Only build the summary of the sweep in this directory");
    sweep->callback([o, &action] { action = [o] { return sweepCommand(*o); }; });

    struct TaskOptions {
        std::string dir;
        int index = -1, threads = 1;
    };
    auto t = std::make_shared<TaskOptions>();
    auto* task = app.add_subcommand("sweep-task", "One variant of a sweep (spall sweep starts these)");
    task->group("");  // internal: not listed in --help
    task->add_option("dir", t->dir, "The sweep's directory")->required();
    task->add_option("--index", t->index, "The variant (default: SLURM_ARRAY_TASK_ID)");
    task->add_option("--threads", t->threads, "Threads")->check(CLI::Range(1, 1024));
    task->callback([t, &action] { action = [t] { return sweepTaskCommand(t->dir, t->index, t->threads); }; });
}
