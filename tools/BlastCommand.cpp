// `spall blast`: blast-wave parameters of a charge at a distance, and its pressure history.
#include "Commands.h"

#include <memory>

#include <spall/blast/Blast.h>
#include <spall/core/Error.h>
#include <spall/output/Png.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

namespace {

/// The pressure history at the point, from detonation to past the negative phase: a plot for
/// .png, else CSV.
void writePressureCurve(const spall::BlastParameters& p, const std::string& path, const std::string& title)
{
    const double end = p.arrivalTimeS + 1.2 * (p.positiveDurationS + p.negativeDurationS);
    const int samples = 2000;
    std::vector<double> times, pressures;
    for (int i = 0; i <= samples; ++i) {
        times.push_back(end * i / samples);
        pressures.push_back(spall::overpressureAt(p, times.back()));
    }
    if (path.size() > 4 && path.substr(path.size() - 4) == ".png") {
        std::vector<double> ms(times.size()), kPa(pressures.size());
        for (size_t i = 0; i < times.size(); ++i) {
            ms[i] = times[i] * 1e3;
            kPa[i] = pressures[i] * 1e-3;
        }
        spall::writePng(path, spall::plotCurve(ms, kPa, "time after detonation (ms)", "overpressure (kPa)", title));
        return;
    }
    std::ofstream out(path);
    if (!out) throw spall::IoError(path + ": cannot write");
    out << "time_s,overpressure_Pa\n";
    for (size_t i = 0; i < times.size(); ++i) out << times[i] << "," << pressures[i] << "\n";
    if (!out) throw spall::IoError(path + ": write failed");
}

/// The burst a charge at `heightM` above the ground is (the scene's rule): surface within
/// surfaceBurstHeightM, else free air; a named surface burst well above the ground is an error.
std::string burstForHeight(double tntKg, double heightM, const std::string& named)
{
    const bool nearGround = heightM <= spall::surfaceBurstHeightM(tntKg);
    if (named.empty()) return nearGround ? "surface" : "free-air";
    if (named == "surface" && !nearGround)
    {
        std::ostringstream reason;
        reason << "--burst surface: the charge is " << heightM << " m above the ground; a surface burst of " << tntKg << " kg sits within "
               << spall::surfaceBurstHeightM(tntKg) << " m of it (--height-m alone picks the burst)";
        throw spall::InputError(reason.str());
    }
    return named;
}

int runBlast(double tntKg, double distanceM, const std::string& burstName, const std::string& datasetName, bool json,
             const std::string& curvePath)
{
    const auto burst = parseOption<spall::BurstType>("--burst", burstName);
    const auto dataset = parseOption<spall::BlastDataset>("--dataset", datasetName);
    const spall::BlastParameters p = spall::blastParameters(dataset, burst, tntKg, distanceM);
    std::string warning;
    if (p.status == spall::RangeStatus::ClampedNear)
        warning = "scaled distance is nearer than the dataset's fits reach: values are held at the fits' near end";
    else if (p.status == spall::RangeStatus::ExtrapolatedFar)
        warning = "scaled distance is beyond the dataset's fits: values are extrapolated (power laws, sound speed)";
    if (!warning.empty()) std::cerr << "spall blast: warning: " << warning << "\n";

    if (!curvePath.empty()) {
        char title[160];
        std::snprintf(title, sizeof title, "%g kg TNT at %g m (Z %.3g)", tntKg, distanceM, p.scaledDistanceMKg13);
        writePressureCurve(p, curvePath, title);
    }
    if (json) {
        nlohmann::json j = {{"tnt_kg", tntKg},
                            {"distance_m", distanceM},
                            {"burst", burstName},
                            {"dataset", datasetName},
                            {"scaled_distance_m_kg13", p.scaledDistanceMKg13},
                            {"peak_overpressure_Pa", p.peakOverpressurePa},
                            {"arrival_time_s", p.arrivalTimeS},
                            {"positive_duration_s", p.positiveDurationS},
                            {"decay_coefficient", p.decayCoefficient},
                            {"positive_impulse_Pa_s", p.positiveImpulsePaS},
                            {"negative_peak_Pa", p.negativePeakPa},
                            {"negative_duration_s", p.negativeDurationS},
                            {"reflected_pressure_Pa", p.reflectedPressurePa},
                            {"reflected_impulse_Pa_s", p.reflectedImpulsePaS},
                            {"shock_speed_m_s", p.shockSpeedMS}};
        if (!warning.empty()) j["warning"] = warning;
        std::cout << j.dump(2) << "\n";
        return 0;
    }
    std::printf("%g kg TNT, %s burst, at %g m (%s)\n", tntKg, burstName.c_str(), distanceM, datasetName.c_str());
    std::printf("  scaled distance       %12.5g m/kg^(1/3)\n", p.scaledDistanceMKg13);
    std::printf("  peak overpressure     %12.5g kPa\n", p.peakOverpressurePa * 1e-3);
    std::printf("  arrival time          %12.5g ms\n", p.arrivalTimeS * 1e3);
    std::printf("  positive duration     %12.5g ms\n", p.positiveDurationS * 1e3);
    std::printf("  positive impulse      %12.5g kPa ms\n", p.positiveImpulsePaS);
    std::printf("  decay coefficient b   %12.5g\n", p.decayCoefficient);
    std::printf("  negative peak         %12.5g kPa\n", p.negativePeakPa * 1e-3);
    std::printf("  negative duration     %12.5g ms\n", p.negativeDurationS * 1e3);
    std::printf("  reflected pressure    %12.5g kPa\n", p.reflectedPressurePa * 1e-3);
    std::printf("  reflected impulse     %12.5g kPa ms\n", p.reflectedImpulsePaS);
    std::printf("  shock speed           %12.5g m/s\n", p.shockSpeedMS);
    return 0;
}

}  // namespace

void addBlastCommand(CLI::App& app, CommandAction& action)
{
    struct Options {
        double tntKg = 0, distanceM = 0, heightM = 0;
        std::string burst = "free-air", dataset = "kingery-bulmash", curve;
        bool json = false;
    };
    auto o = std::make_shared<Options>();
    auto* sub = app.add_subcommand("blast", "Print blast-wave parameters of a TNT charge at a distance");
    sub->add_option("--tnt-kg", o->tntKg, "Charge mass (kg TNT)")->required();
    sub->add_option("--distance-m", o->distanceM, "Distance from the charge (m)")->required();
    auto* burst = sub->add_option("--burst", o->burst, "free-air | surface (default: free-air, or from --height-m)");
    auto* height = sub->add_option("--height-m", o->heightM, "Height of the charge above the ground (m): surface burst within two charge radii")
                       ->check(CLI::NonNegativeNumber);
    sub->add_option("--dataset", o->dataset, "kingery-bulmash | kinney-graham");
    sub->add_flag("--json", o->json, "JSON with SI units in every key");
    sub->add_option("--curve", o->curve, "Write the pressure history: .csv, or .png for a plot");
    sub->callback([o, burst, height, &action] {
        const bool fromHeight = height->count() > 0, named = burst->count() > 0;
        action = [o, fromHeight, named] {
            const std::string burstName = fromHeight ? burstForHeight(o->tntKg, o->heightM, named ? o->burst : "") : o->burst;
            return runBlast(o->tntKg, o->distanceM, burstName, o->dataset, o->json, o->curve);
        };
    });
}
