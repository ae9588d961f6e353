#include <spall/sweep/Sweep.h>

#include <spall/core/AtomicFile.h>
#include <spall/output/H5Out.h>
#include <spall/output/Png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>

namespace spall {

namespace {

/// Student's t at 97.5 % for 1 … 30 degrees of freedom (any statistics table, e.g. NIST/SEMATECH
/// e-Handbook 1.3.6.7.2); beyond, 1.96 + 2.5/df, within 0.1 % of the table.
double studentT975(int64_t dof)
{
    static const double table[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160, 2.145, 2.131,
                                   2.120,  2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042};
    return dof <= 30 ? table[dof - 1] : 1.96 + 2.5 / static_cast<double>(dof);
}

VariantFigures figuresOf(const DebrisReport& r)
{
    return {r.debrisCount(), r.hazardousCount(), r.maxThrowDistanceM, r.medianThrowDistanceM, r.hazardousFragmentDistanceM,
            r.worstSectorHazardousFragmentDistanceM, r.massFit.shape};
}

struct Figure {
    const char* key;
    double (*get)(const VariantFigures&);
};
const Figure kFigures[] = {
    {"fragments", [](const VariantFigures& f) { return double(f.fragments); }},
    {"hazardous", [](const VariantFigures& f) { return double(f.hazardous); }},
    {"max_throw_distance_m", [](const VariantFigures& f) { return f.maxThrowDistanceM; }},
    {"median_throw_distance_m", [](const VariantFigures& f) { return f.medianThrowDistanceM; }},
    {"hazardous_fragment_distance_m", [](const VariantFigures& f) { return f.hazardousFragmentDistanceM; }},
    {"worst_sector_hazardous_fragment_distance_m", [](const VariantFigures& f) { return f.worstSectorHazardousFragmentDistanceM; }},
    {"weibull_shape", [](const VariantFigures& f) { return f.weibullShape; }},
};

std::string csvQuoted(const std::string& s)
{
    std::string out = "\"";
    for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c == '\n' ? ' ' : c);
    return out + "\"";
}

std::vector<double> doneValues(const SweepSummary& s, const std::vector<int>& group, const Figure& figure)
{
    std::vector<double> values;
    for (int i : group)
        if (s.status[i].state == VariantState::Done) values.push_back(figure.get(s.figures[i]));
    return values;
}

}  // namespace

bool seedsChangedAnything(const SweepSummary& summary, const std::vector<int>& group)
{
    for (const Figure& figure : kFigures) {
        const std::vector<double> values = doneValues(summary, group, figure);
        if (values.size() < 2) return true;  // nothing to compare: no claim that seeds do nothing
        const auto differs = [&](double v) { return v != values.front() && !(std::isnan(v) && std::isnan(values.front())); };
        if (std::any_of(values.begin(), values.end(), differs)) return true;
    }
    return false;
}

namespace {

void writeVariantsCsv(std::ostream& out, const SweepPlan& plan, const SweepSummary& s)
{
    out << "index,name,seed,overrides,state,message";
    for (const Figure& f : kFigures) out << "," << f.key;
    out << "\n";
    for (const SweepVariant& v : plan.variants) {
        out << v.index << "," << v.name() << "," << v.seed << "," << csvQuoted(v.overridesText()) << "," << enumName(s.status[v.index].state)
            << "," << csvQuoted(s.status[v.index].message);
        for (const Figure& f : kFigures) {
            char value[32];
            std::snprintf(value, sizeof value, "%.9g", f.get(s.figures[v.index]));
            out << "," << (s.status[v.index].state == VariantState::Done ? value : "");
        }
        out << "\n";
    }
}

void writeGroupsCsv(std::ostream& out, const SweepPlan& plan, const SweepSummary& s)
{
    out << "group,overrides,variants,done,seeds_changed_anything";
    for (const Figure& f : kFigures) out << "," << f.key << "_mean," << f.key << "_ci95_half_width," << f.key << "_min," << f.key << "_max";
    out << "\n";
    for (size_t g = 0; g < s.groups.size(); ++g) {
        out << g << "," << csvQuoted(plan.variants[s.groups[g].front()].overridesText()) << "," << s.groups[g].size() << ","
            << doneValues(s, s.groups[g], kFigures[0]).size() << "," << int(seedsChangedAnything(s, s.groups[g]));
        for (const Figure& f : kFigures) {
            const MeanInterval m = meanInterval(doneValues(s, s.groups[g], f));
            char line[160];
            std::snprintf(line, sizeof line, ",%.9g,%.9g,%.9g,%.9g", m.mean, m.halfWidth, m.min, m.max);
            out << line;
        }
        out << "\n";
    }
}

void writeSummaryH5(H5Out& h5, const SweepPlan& plan, const SweepSummary& s)
{
    h5.attribute("format_version", int64_t{1});
    h5.attribute("variants", static_cast<int64_t>(plan.variants.size()));
    h5.group("/variants");
    std::vector<int64_t> seed, state, group(plan.variants.size());
    for (const SweepVariant& v : plan.variants) {
        seed.push_back(static_cast<int64_t>(v.seed));
        state.push_back(static_cast<int64_t>(s.status[v.index].state));
    }
    for (size_t g = 0; g < s.groups.size(); ++g)
        for (int i : s.groups[g]) group[i] = static_cast<int64_t>(g);
    h5.write("/variants/seed", seed);
    h5.write("/variants/state", state);  // 0 pending, 1 done, 2 stopped, 3 failed
    h5.write("/variants/group", group);
    h5.group("/groups");
    for (const Figure& f : kFigures) {
        std::vector<double> values, mean, half;
        for (const SweepVariant& v : plan.variants)
            values.push_back(s.status[v.index].state == VariantState::Done ? f.get(s.figures[v.index]) : std::nan(""));
        for (const auto& g : s.groups) {
            const MeanInterval m = meanInterval(doneValues(s, g, f));
            mean.push_back(m.mean);
            half.push_back(m.halfWidth);
        }
        h5.write(("/variants/" + std::string(f.key)).c_str(), values);
        h5.write(("/groups/" + std::string(f.key) + "_mean").c_str(), mean);
        h5.write(("/groups/" + std::string(f.key) + "_ci95_half_width").c_str(), half);
    }
}

/// The hazardous fragment distance over seeds: each group's values, sorted, against the fraction
/// of its seeds at or below them.
Image hazardDistancePlot(const SweepPlan& plan, const SweepSummary& s)
{
    std::vector<PlotSeries> series;
    for (const auto& g : s.groups) {
        std::vector<double> values = doneValues(s, g, kFigures[4]);
        std::sort(values.begin(), values.end());
        PlotSeries line{plan.axes.empty() ? "all seeds" : plan.variants[g.front()].overridesText(), {}, {}};
        for (size_t i = 0; i < values.size(); ++i) {
            line.x.push_back(values[i]);
            line.y.push_back(double(i + 1) / values.size());
        }
        if (series.size() < 8) series.push_back(line);
    }
    return plotSeries(series, "hazardous fragment distance (m)", "fraction of seeds", "hazardous fragment distance over seeds", PlotScale::Linear);
}

}  // namespace

MeanInterval meanInterval(const std::vector<double>& values)
{
    MeanInterval m;
    m.n = static_cast<int64_t>(values.size());
    const double nan = std::numeric_limits<double>::quiet_NaN();
    if (values.empty()) return {0, nan, nan, nan, nan};
    double sum = 0;
    for (double v : values) sum += v;
    m.mean = sum / m.n;
    m.min = *std::min_element(values.begin(), values.end());
    m.max = *std::max_element(values.begin(), values.end());
    if (m.n < 2) {
        m.halfWidth = nan;
        return m;
    }
    double squares = 0;
    for (double v : values) squares += (v - m.mean) * (v - m.mean);
    m.halfWidth = studentT975(m.n - 1) * std::sqrt(squares / (m.n - 1) / m.n);
    return m;
}

SweepSummary collectSweep(const std::string& sweepDir, const SweepPlan& plan)
{
    SweepSummary s;
    std::map<std::string, size_t> groupOf;
    for (const SweepVariant& v : plan.variants) {
        VariantStatus status = readVariantStatus(sweepDir, v);
        VariantFigures figures;
        if (status.state == VariantState::Done) try {
                figures = figuresOf(analyseDebris(readHistory(variantOutputDirectory(sweepDir, v) + "/history.h5")));
            } catch (const std::exception& e) {
                status = {VariantState::Failed, std::string("its results cannot be read: ") + e.what()};
            }
        s.status.push_back(status);
        s.figures.push_back(figures);
        const auto [at, added] = groupOf.insert({v.overridesText(), s.groups.size()});
        if (added) s.groups.emplace_back();
        s.groups[at->second].push_back(v.index);
    }
    return s;
}

void writeSweepSummary(const std::string& sweepDir, const SweepPlan& plan, const SweepSummary& summary)
{
    writeH5FileAtomically(sweepDir + "/summary.h5", [&](H5Out& h5) { writeSummaryH5(h5, plan, summary); });
    writeFileAtomically(sweepDir + "/summary.csv", [&](std::ostream& out) { writeVariantsCsv(out, plan, summary); });
    writeFileAtomically(sweepDir + "/summary_groups.csv", [&](std::ostream& out) { writeGroupsCsv(out, plan, summary); });
    writePng(sweepDir + "/summary_hfd.png", hazardDistancePlot(plan, summary));
}

}  // namespace spall
