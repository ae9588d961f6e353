#include <spall/dynamics/BroadPhase.h>

#include <spall/core/Parallel.h>
#include <spall/dynamics/Integrate.h>

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

namespace spall {

bool pairCanInteract(const Body& a, const Body& b) { return movable(a) || movable(b); }

std::vector<BodyPair> findCandidatePairs(const std::vector<Body>& bodies)
{
    if (bodies.empty()) return {};
    // A hierarchical grid: level k has cells base * 2^k wide, and a body lives at the finest
    // level whose cells are at least its bounding diameter, in the cell of its centre. Two
    // overlapping spheres are then at most one cell apart on the coarser one's level, so each
    // occupied cell looks in the 27 cells around it on its own level and around its parent on
    // every coarser occupied level.
    // Work follows the bodies and their neighbours, whatever their sizes and however densely
    // packed (a sweep along one axis grows as n^(5/3) in a packed 3-D cloud).
    double smallest = std::numeric_limits<double>::infinity();
    for (const Body& b : bodies) smallest = std::min(smallest, b.boundingRadiusM);
    const double base = 2.0 * std::max(smallest, 1e-9);
    auto levelOf = [&](double radius) {
        int level = 0;
        while (base * std::ldexp(1.0, level) < 2.0 * radius && level < 60) ++level;
        return level;
    };
    struct Cell {
        int level;
        int64_t z, y, x;
        bool operator<(const Cell& o) const { return std::tie(level, z, y, x) < std::tie(o.level, o.z, o.y, o.x); }
    };
    auto cellAt = [&](const Eigen::Vector3d& p, int level) {
        const double size = base * std::ldexp(1.0, level);
        return Cell{level, static_cast<int64_t>(std::floor(p.z() / size)), static_cast<int64_t>(std::floor(p.y() / size)),
                    static_cast<int64_t>(std::floor(p.x() / size))};
    };
    std::vector<std::pair<Cell, int>> entries(bodies.size());
    forEachIndex(bodies.size(), [&](size_t i) {
        entries[i] = {cellAt(bodies[i].positionM, levelOf(bodies[i].boundingRadiusM)), static_cast<int>(i)};
    }, kCheapGrain);
    std::sort(entries.begin(), entries.end(),
              [](const auto& x, const auto& y) { return x.first < y.first || (!(y.first < x.first) && x.second < y.second); });
    // Occupied cells as runs of entries; the bodies of one cell share every search.
    struct Run {
        Cell cell;
        size_t begin, end;
    };
    std::vector<Run> runs;
    for (size_t k = 0; k < entries.size(); ++k) {
        if (runs.empty() || runs.back().cell < entries[k].first) runs.push_back({entries[k].first, k, k});
        runs.back().end = k + 1;
    }
    std::vector<int> levels;
    for (const Run& r : runs)
        if (levels.empty() || levels.back() != r.cell.level) levels.push_back(r.cell.level);
    auto floorHalf = [](int64_t v, int shift) { return v >= 0 ? v >> shift : -((-v + (int64_t(1) << shift) - 1) >> shift); };
    constexpr size_t kBlock = 64;
    std::vector<std::vector<BodyPair>> found((runs.size() + kBlock - 1) / kBlock);
    forEachIndex(found.size(), [&](size_t block) {
        auto test = [&](int i, int j) {
            const Body& a = bodies[i];
            const Body& b = bodies[j];
            const double reach = a.boundingRadiusM + b.boundingRadiusM;
            if ((a.positionM - b.positionM).squaredNorm() > reach * reach || !pairCanInteract(a, b)) return;
            found[block].push_back({std::min(i, j), std::max(i, j)});
        };
        for (size_t r = block * kBlock; r < std::min(runs.size(), (block + 1) * kBlock); ++r) {
            const Run& run = runs[r];
            for (size_t p = run.begin; p < run.end; ++p)
                for (size_t q = p + 1; q < run.end; ++q) test(entries[p].second, entries[q].second);
            for (int l : levels) {
                if (l < run.cell.level) continue;
                // This cell's cell on level l (cells nest: each is half its parent's width).
                const int shift = l - run.cell.level;
                const Cell centre{l, floorHalf(run.cell.z, shift), floorHalf(run.cell.y, shift), floorHalf(run.cell.x, shift)};
                for (int64_t dz = -1; dz <= 1; ++dz)
                    for (int64_t dy = -1; dy <= 1; ++dy) {
                        // Cells (z, y, x - 1 .. x + 1) are contiguous among the runs.
                        const Cell first{l, centre.z + dz, centre.y + dy, centre.x - 1};
                        auto it = std::lower_bound(runs.begin(), runs.end(), first, [](const Run& x, const Cell& c) { return x.cell < c; });
                        for (; it != runs.end() && it->cell.level == l && it->cell.z == first.z && it->cell.y == first.y &&
                               it->cell.x <= centre.x + 1;
                             ++it) {
                            // On its own level each pair of cells once, from the lower; a coarser
                            // cell never looks down, so the finer one reports the pair.
                            if (shift == 0 && !(run.cell < it->cell)) continue;
                            for (size_t p = run.begin; p < run.end; ++p)
                                for (size_t q = it->begin; q < it->end; ++q) test(entries[p].second, entries[q].second);
                        }
                    }
            }
        }
    });
    std::vector<BodyPair> pairs;
    for (const auto& f : found) pairs.insert(pairs.end(), f.begin(), f.end());
    tbb::parallel_sort(pairs.begin(), pairs.end());  // pairs are unique: the order is
    return pairs;
}

}  // namespace spall
