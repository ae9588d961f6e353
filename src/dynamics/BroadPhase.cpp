#include <spall/dynamics/BroadPhase.h>

#include <spall/core/Parallel.h>
#include <spall/dynamics/Integrate.h>

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

namespace spall {

bool pairCanInteract(const Body& a, const Body& b)
{
    return (takesContactImpulses(a) || takesContactImpulses(b)) && !(a.motion.deformable && b.motion.deformable);
}

namespace {

/// A hierarchical grid over bounding spheres: level k has cells base * 2^k wide (base: the
/// smallest bounding diameter), and a body lives at the finest level whose cells are at least
/// its diameter, in the cell of its centre. Two overlapping spheres are then at most one cell
/// apart on the coarser one's level, so each occupied cell looks in the 27 cells around it on
/// its own level and around its parent on every coarser occupied level. Work follows the bodies
/// and their neighbours, whatever their sizes and however densely packed (a sweep along one
/// axis grows as n^(5/3) in a packed 3-D cloud).
class HierarchicalGrid {
public:
    struct Cell {
        int level;
        int64_t z, y, x;
        bool operator<(const Cell& o) const { return std::tie(level, z, y, x) < std::tie(o.level, o.z, o.y, o.x); }
    };
    /// An occupied cell: entries [begin, end) of bodyOfEntry.
    struct Run {
        Cell cell;
        size_t begin, end;
    };

    HierarchicalGrid(const std::vector<Eigen::Vector3d>& centresM, const std::vector<double>& radiiM)
    {
        double smallest = std::numeric_limits<double>::infinity();
        for (const double r : radiiM) smallest = std::min(smallest, r);
        mBase = 2.0 * std::max(smallest, 1e-9);
        std::vector<std::pair<Cell, int>> entries(centresM.size());
        forEachIndex(centresM.size(), [&](size_t i) { entries[i] = {cellAt(centresM[i], levelOf(radiiM[i])), static_cast<int>(i)}; }, kCheapGrain);
        std::sort(entries.begin(), entries.end(),
                  [](const auto& x, const auto& y) { return x.first < y.first || (!(y.first < x.first) && x.second < y.second); });
        // Occupied cells as runs of entries; the bodies of one cell share every search.
        for (size_t k = 0; k < entries.size(); ++k) {
            if (mRuns.empty() || mRuns.back().cell < entries[k].first) mRuns.push_back({entries[k].first, k, k});
            mRuns.back().end = k + 1;
            mBodyOfEntry.push_back(entries[k].second);
        }
        for (const Run& r : mRuns)
            if (mLevels.empty() || mLevels.back() != r.cell.level) mLevels.push_back(r.cell.level);
    }

    const std::vector<Run>& runs() const { return mRuns; }
    int body(size_t entry) const { return mBodyOfEntry[entry]; }

    /// Calls f(other) for every run that may hold a body overlapping one of `run`'s: on its own
    /// level each pair of cells once, from the lower; a coarser cell never looks down, so the
    /// finer one reports the pair.
    template <typename F>
    void forEachNeighbourRun(const Run& run, F&& f) const
    {
        for (int l : mLevels) {
            if (l < run.cell.level) continue;
            // This cell's cell on level l (cells nest: each is half its parent's width).
            const int shift = l - run.cell.level;
            const Cell centre{l, floorShift(run.cell.z, shift), floorShift(run.cell.y, shift), floorShift(run.cell.x, shift)};
            for (int64_t dz = -1; dz <= 1; ++dz)
                for (int64_t dy = -1; dy <= 1; ++dy) {
                    // Cells (z, y, x - 1 .. x + 1) are contiguous among the runs.
                    const Cell first{l, centre.z + dz, centre.y + dy, centre.x - 1};
                    auto it = std::lower_bound(mRuns.begin(), mRuns.end(), first, [](const Run& x, const Cell& c) { return x.cell < c; });
                    for (; it != mRuns.end() && it->cell.level == l && it->cell.z == first.z && it->cell.y == first.y &&
                           it->cell.x <= centre.x + 1;
                         ++it)
                        if (shift != 0 || run.cell < it->cell) f(*it);
                }
        }
    }

private:
    int levelOf(double radius) const
    {
        int level = 0;
        while (mBase * std::ldexp(1.0, level) < 2.0 * radius && level < 60) ++level;
        return level;
    }
    Cell cellAt(const Eigen::Vector3d& p, int level) const
    {
        const double size = mBase * std::ldexp(1.0, level);
        return Cell{level, static_cast<int64_t>(std::floor(p.z() / size)), static_cast<int64_t>(std::floor(p.y() / size)),
                    static_cast<int64_t>(std::floor(p.x() / size))};
    }
    static int64_t floorShift(int64_t v, int shift) { return v >= 0 ? v >> shift : -((-v + (int64_t(1) << shift) - 1) >> shift); }

    double mBase = 1;
    std::vector<Run> mRuns;
    std::vector<int> mBodyOfEntry;
    std::vector<int> mLevels;  ///< occupied levels, ascending
};

/// Pairs of spheres that overlap and that `keep(i, j)` keeps, sorted.
template <typename Keep>
std::vector<BodyPair> overlappingSpheres(const std::vector<Eigen::Vector3d>& centresM, const std::vector<double>& radiiM, Keep&& keep)
{
    if (centresM.empty()) return {};
    const HierarchicalGrid grid(centresM, radiiM);
    const auto& runs = grid.runs();
    constexpr size_t kBlock = 64;
    std::vector<std::vector<BodyPair>> found((runs.size() + kBlock - 1) / kBlock);
    forEachIndex(found.size(), [&](size_t block) {
        auto test = [&](int i, int j) {
            const double reach = radiiM[size_t(i)] + radiiM[size_t(j)];
            if ((centresM[size_t(i)] - centresM[size_t(j)]).squaredNorm() > reach * reach || !keep(i, j)) return;
            found[block].push_back({std::min(i, j), std::max(i, j)});
        };
        for (size_t r = block * kBlock; r < std::min(runs.size(), (block + 1) * kBlock); ++r) {
            const auto& run = runs[r];
            for (size_t p = run.begin; p < run.end; ++p)
                for (size_t q = p + 1; q < run.end; ++q) test(grid.body(p), grid.body(q));
            grid.forEachNeighbourRun(run, [&](const HierarchicalGrid::Run& other) {
                for (size_t p = run.begin; p < run.end; ++p)
                    for (size_t q = other.begin; q < other.end; ++q) test(grid.body(p), grid.body(q));
            });
        }
    });
    std::vector<BodyPair> pairs;
    for (const auto& f : found) pairs.insert(pairs.end(), f.begin(), f.end());
    tbb::parallel_sort(pairs.begin(), pairs.end());  // pairs are unique: the order is
    return pairs;
}

std::vector<Eigen::Vector3d> centresOf(const std::vector<Body>& bodies)
{
    std::vector<Eigen::Vector3d> centres(bodies.size());
    for (size_t i = 0; i < bodies.size(); ++i) centres[i] = bodies[i].motion.positionM;
    return centres;
}

}  // namespace

std::vector<BodyPair> findCandidatePairs(const std::vector<Body>& bodies)
{
    std::vector<double> radii(bodies.size());
    for (size_t i = 0; i < bodies.size(); ++i) radii[i] = bodies[i].boundingRadiusM;
    return overlappingSpheres(centresOf(bodies), radii, [&](int i, int j) { return pairCanInteract(bodies[size_t(i)], bodies[size_t(j)]); });
}

std::vector<char> withinReachOfAnotherBody(const std::vector<Body>& bodies, const std::vector<double>& reachM)
{
    std::vector<double> radii(bodies.size());
    for (size_t i = 0; i < bodies.size(); ++i) radii[i] = bodies[i].boundingRadiusM + reachM[i];
    std::vector<char> near(bodies.size(), 0);
    for (const BodyPair& p : overlappingSpheres(centresOf(bodies), radii, [](int, int) { return true; })) near[size_t(p.a)] = near[size_t(p.b)] = 1;
    return near;
}

}  // namespace spall
