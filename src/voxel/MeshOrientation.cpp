#include "MeshOrientation.h"

#include "WindingNumber.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>

namespace spall {

namespace {

/// Every (undirected edge, triangle) use, sorted by edge and then triangle: the triangles that
/// share an edge are one run of equal keys.
class EdgeUses {
public:
    explicit EdgeUses(const TriangleMesh& mesh)
    {
        mUses.reserve(3 * mesh.triangles.size());
        for (int t = 0; t < static_cast<int>(mesh.triangles.size()); ++t)
            for (int e = 0; e < 3; ++e) mUses.push_back({key(mesh.triangles[t][e], mesh.triangles[t][(e + 1) % 3]), t});
        std::sort(mUses.begin(), mUses.end());
    }

    /// The other triangle across edge (a, b) of triangle t, or -1 when the edge is open or shared
    /// by more than two triangles (no neighbour to agree with).
    int across(int a, int b, int t) const
    {
        const auto [first, last] = std::equal_range(mUses.begin(), mUses.end(), std::pair<uint64_t, int>{key(a, b), -1},
                                                    [](const auto& x, const auto& y) { return x.first < y.first; });
        if (last - first != 2) return -1;
        return first->second == t ? (first + 1)->second : first->second;
    }

    /// Edges not used by exactly two triangles.
    int64_t openEdges() const
    {
        int64_t open = 0;
        for (size_t run = 0, next = 0; run < mUses.size(); run = next) {
            while (next < mUses.size() && mUses[next].first == mUses[run].first) ++next;
            open += (next - run != 2);
        }
        return open;
    }

private:
    static uint64_t key(int a, int b) { return (uint64_t(uint32_t(std::min(a, b))) << 32) | uint32_t(std::max(a, b)); }

    std::vector<std::pair<uint64_t, int>> mUses;
};

/// True when triangle t runs from a to b along one of its edges.
bool runsFromTo(const Eigen::Vector3i& t, int a, int b)
{
    for (int e = 0; e < 3; ++e)
        if (t[e] == a && t[(e + 1) % 3] == b) return true;
    return false;
}

void turn(Eigen::Vector3i& t) { std::swap(t[1], t[2]); }

/// Six times the volume of the cone from `apex` over the triangles of one shell (signed).
double sixConeVolume(const TriangleMesh& mesh, const std::vector<int>& shell, const Eigen::Vector3d& apex)
{
    double sixV = 0.0;
    for (int t : shell) {
        const Eigen::Vector3d a = mesh.positionsM[mesh.triangles[t][0]].cast<double>() - apex;
        const Eigen::Vector3d b = mesh.positionsM[mesh.triangles[t][1]].cast<double>() - apex;
        const Eigen::Vector3d c = mesh.positionsM[mesh.triangles[t][2]].cast<double>() - apex;
        sixV += a.dot(b.cross(c));
    }
    return sixV;
}

Eigen::Vector3d vertexMean(const TriangleMesh& mesh, const std::vector<int>& shell)
{
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int t : shell)
        for (int k = 0; k < 3; ++k) sum += mesh.positionsM[mesh.triangles[t][k]].cast<double>();
    return sum / (3.0 * static_cast<double>(shell.size()));
}

/// Shells: triangles joined across two-triangle edges (a breadth-first walk), turning each
/// newly reached triangle to run the shared edge the other way from the one it came from.
std::vector<std::vector<int>> walkShells(TriangleMesh& mesh, const EdgeUses& uses)
{
    const int n = static_cast<int>(mesh.triangles.size());
    std::vector<char> reached(n, 0);
    std::vector<std::vector<int>> shells;
    for (int seed = 0; seed < n; ++seed) {
        if (reached[seed]) continue;
        reached[seed] = 1;
        std::vector<int> shell{seed};
        for (size_t next = 0; next < shell.size(); ++next) {
            const Eigen::Vector3i t = mesh.triangles[shell[next]];
            for (int e = 0; e < 3; ++e) {
                const int a = t[e], b = t[(e + 1) % 3];
                const int other = uses.across(a, b, shell[next]);
                if (other < 0 || reached[other]) continue;
                reached[other] = 1;
                if (runsFromTo(mesh.triangles[other], a, b)) turn(mesh.triangles[other]);
                shell.push_back(other);
            }
        }
        shells.push_back(std::move(shell));
    }
    return shells;
}

Eigen::AlignedBox3d shellBounds(const TriangleMesh& mesh, const std::vector<int>& shell)
{
    Eigen::AlignedBox3d bounds;
    for (int t : shell)
        for (int k = 0; k < 3; ++k) bounds.extend(mesh.positionsM[mesh.triangles[t][k]].cast<double>());
    return bounds;
}

/// Whether every edge of the shell's triangles is shared with exactly one other triangle.
bool shellIsClosed(const TriangleMesh& mesh, const EdgeUses& uses, const std::vector<int>& shell)
{
    for (int t : shell)
        for (int e = 0; e < 3; ++e)
            if (uses.across(mesh.triangles[t][e], mesh.triangles[t][(e + 1) % 3], t) < 0) return false;
    return true;
}

/// Per shell, the outermost closed shell that holds it (a vertex of it has a winding number of
/// magnitude above one half about that shell), or -1 when none does.
std::vector<int> outermostHolders(const TriangleMesh& mesh, const EdgeUses& uses, const std::vector<std::vector<int>>& shells)
{
    std::vector<Eigen::AlignedBox3d> bounds;
    for (const auto& shell : shells) bounds.push_back(shellBounds(mesh, shell));
    std::vector<int> outermost(shells.size(), -1);
    for (size_t holder = 0; holder < shells.size(); ++holder) {
        std::vector<size_t> candidates;
        for (size_t s = 0; s < shells.size(); ++s)
            if (s != holder && bounds[holder].contains(bounds[s])) candidates.push_back(s);
        if (candidates.empty() || !shellIsClosed(mesh, uses, shells[holder])) continue;
        TriangleMesh holderMesh{mesh.positionsM, {}};
        for (int t : shells[holder]) holderMesh.triangles.push_back(mesh.triangles[t]);
        const WindingNumberField field(holderMesh);
        for (const size_t s : candidates) {
            const Eigen::Vector3d vertex = mesh.positionsM[mesh.triangles[shells[s].front()][0]].cast<double>();
            const bool larger = outermost[s] < 0 || bounds[holder].volume() > bounds[size_t(outermost[s])].volume();
            if (larger && std::abs(field.at(vertex)) > 0.5) outermost[s] = int(holder);
        }
    }
    return outermost;
}

/// Merges vertices at equal positions (readers keep copies per face normal or texture seam) and
/// drops triangles that two of their corners then share, which bound nothing.
void weldEqualPositions(TriangleMesh& mesh)
{
    // Sorted by position, then index: each run of equal positions maps to its first vertex, and the
    // kept vertices stay in the order they came.
    const auto& p = mesh.positionsM;
    std::vector<int> order(p.size());
    std::iota(order.begin(), order.end(), 0);
    const auto position = [&](int v) { return std::array<float, 3>{p[v].x(), p[v].y(), p[v].z()}; };
    std::sort(order.begin(), order.end(), [&](int x, int y) { return std::pair(position(x), x) < std::pair(position(y), y); });
    std::vector<int> welded(p.size());
    for (size_t i = 0; i < order.size(); ++i)
        welded[order[i]] = (i > 0 && position(order[i]) == position(order[i - 1])) ? welded[order[i - 1]] : order[i];
    std::vector<int> newIndex(p.size());
    std::vector<Eigen::Vector3f> unique;
    for (size_t v = 0; v < p.size(); ++v) {
        if (welded[v] != static_cast<int>(v)) continue;
        newIndex[v] = static_cast<int>(unique.size());
        unique.push_back(p[v]);
    }
    for (int& w : welded) w = newIndex[w];
    std::vector<Eigen::Vector3i> kept;
    kept.reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles) {
        const Eigen::Vector3i w(welded[t[0]], welded[t[1]], welded[t[2]]);
        if (w[0] != w[1] && w[1] != w[2] && w[2] != w[0]) kept.push_back(w);
    }
    mesh.positionsM = std::move(unique);
    mesh.triangles = std::move(kept);
}

}  // namespace

MeshTopology orientOutward(TriangleMesh& mesh)
{
    MeshTopology topology;
    weldEqualPositions(mesh);
    const std::vector<Eigen::Vector3i> asGiven = mesh.triangles;
    const EdgeUses uses(mesh);
    topology.openEdges = uses.openEdges();
    const auto shells = walkShells(mesh, uses);
    const std::vector<int> holders = outermostHolders(mesh, uses, shells);
    std::vector<double> sixVolumes;
    for (const auto& shell : shells) sixVolumes.push_back(sixConeVolume(mesh, shell, vertexMean(mesh, shell)));
    double sixV = 0.0;
    for (size_t i = 0; i < shells.size(); ++i) {
        // A shell no other holds faces outward. One inside another keeps its winding relative to
        // the outermost shell around it, which turns with it: wound against that shell it bounds
        // a hollow (a sealed room, a tank's inside), with it it is a part inside a part (the
        // union stays solid).
        const int holder = holders[i];
        const bool turned = (holder < 0 ? sixVolumes[i] : sixVolumes[size_t(holder)]) < 0.0;
        const double sixOutward = turned ? -sixVolumes[i] : sixVolumes[i];
        if (holder >= 0) topology.hollows += sixOutward < 0.0;
        sixV += sixOutward;
        if (turned)
            for (int t : shells[i]) turn(mesh.triangles[t]);
    }
    topology.enclosedVolumeM3 = sixV / 6.0;
    for (size_t t = 0; t < asGiven.size(); ++t) topology.turnedTriangles += (mesh.triangles[t] != asGiven[t]);
    return topology;
}

}  // namespace spall
