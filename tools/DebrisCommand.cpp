// `spall debris OUTDIR`: where a run's fragments landed and how dangerous they were
// (debris.h5, debris.csv, debris_*.png; definitions in docs/debris.md).
#include "Commands.h"

#include <spall/analysis/Debris.h>

#include <cstdio>
#include <filesystem>
#include <memory>

namespace {

int debrisCommand(const std::string& outDir, const spall::DebrisSettings& settings, bool allowIncomplete)
{
    const std::string historyPath = (std::filesystem::path(outDir) / "history.h5").string();
    const spall::History history = spall::readHistory(historyPath);
    if (!history.runComplete && !allowIncomplete)
        throw spall::InputError(historyPath + ": the run is not complete (finish it with spall run --resume " + outDir +
                                ", or pass --allow-incomplete to analyse the frames so far)");
    const spall::DebrisReport report = spall::analyseDebris(history, settings);
    spall::writeDebrisReport(outDir, report);
    std::printf("%lld fragments thrown (%lld hazardous: at least %.0f J at impact), %zu pieces stayed where they stood\n", static_cast<long long>(report.debrisCount()),
                static_cast<long long>(report.hazardousCount()), settings.hazardousEnergyJ,
                report.fragments.size() - static_cast<size_t>(report.debrisCount()));
    std::printf("throw distance: max %.2f m, median %.2f m, mass median %.2f m\n", report.maxThrowDistanceM, report.medianThrowDistanceM,
                report.massMedianThrowDistanceM);
    if (report.hazardousCount() == 0)
        std::printf("hazardous fragment distance: none, as no fragment is hazardous\n");
    else if (report.worstSectorHazardousFragmentDistanceM == 0)
        std::printf("hazardous fragment distance: none, as hazardous fragments are nowhere denser than 1 per %.1f m2\n", settings.hazardousAreaM2);
    else
        std::printf("hazardous fragment distance (1 per %.1f m2): %.2f m over whole rings, %.2f m in the worst of %d sectors\n",
                    settings.hazardousAreaM2, report.hazardousFragmentDistanceM, report.worstSectorHazardousFragmentDistanceM, settings.sectors);
    if (report.massFit.fragments > 0)
        std::printf("mass: Weibull N(>m) = N exp(-(m/%.4g kg)^%.3f), R2 %.3f over %lld fragments (Mott: exponent 0.5)\n",
                    report.massFit.scaleKg, report.massFit.shape, report.massFit.rSquared, static_cast<long long>(report.massFit.fragments));
    else
        std::printf("mass: no Weibull fit, as a fit needs at least 3 distinct masses among the thrown fragments (%lld thrown)\n",
                    static_cast<long long>(report.debrisCount()));
    std::printf("wrote %s/debris.h5, debris.csv, debris_throw.png, debris_density.png, debris_mass.png\n", outDir.c_str());
    return 0;
}

}  // namespace

void addDebrisCommand(CLI::App& app, CommandAction& action)
{
    struct Options {
        std::string outDir;
        spall::DebrisSettings settings;
        bool allowIncomplete = false;
    };
    auto o = std::make_shared<Options>();
    auto* debris = app.add_subcommand("debris", "Where the fragments landed: throw distances, areal and hazardous densities, mass fit");
    debris->add_option("outdir", o->outDir, "A run's output directory (its history.h5)")->required();
    debris->add_option("--hazardous-energy-J", o->settings.hazardousEnergyJ, "Impact energy of a hazardous fragment (J)")
        ->check(CLI::PositiveNumber)->capture_default_str();
    debris->add_option("--hazardous-area-m2", o->settings.hazardousAreaM2, "One hazardous fragment per this area is the limit (m2)")
        ->check(CLI::PositiveNumber)->capture_default_str();
    debris->add_option("--launch-speed-m-s", o->settings.launchSpeedMS, "A fragment is launched once it moves this fast (m/s)")
        ->check(CLI::PositiveNumber)->capture_default_str();
    debris->add_option("--stay-distance-m", o->settings.stayDistanceM, "A piece resting this close to where it came to be is not debris (m)")
        ->check(CLI::NonNegativeNumber)->capture_default_str();
    debris->add_option("--ring-width-m", o->settings.ringWidthM, "Width of the range rings (m); 0 picks about 20 rings")
        ->check(CLI::NonNegativeNumber)->capture_default_str();
    debris->add_option("--sectors", o->settings.sectors, "Sectors about the charges, the first centred on +x")
        ->check(CLI::Range(1, 360))->capture_default_str();
    debris->add_flag("--allow-incomplete", o->allowIncomplete, "Analyse a run that has not finished");
    debris->callback([o, &action] { action = [o] { return debrisCommand(o->outDir, o->settings, o->allowIncomplete); }; });
}
