#include "MeshOrientation.h"

#include <algorithm>
#include <array>
#include <map>
#include <cmath>

namespace spall {

namespace {

using EdgeKey = std::pair<int, int>;

EdgeKey undirected(int a, int b) { return a < b ? EdgeKey{a, b} : EdgeKey{b, a}; }

/// For every undirected edge, the triangles that use it.
std::map<EdgeKey, std::vector<int>> edgeUses(const TriangleMesh& mesh)
{
    std::map<EdgeKey, std::vector<int>> uses;
    for (int t = 0; t < static_cast<int>(mesh.triangles.size()); ++t)
        for (int e = 0; e < 3; ++e) uses[undirected(mesh.triangles[t][e], mesh.triangles[t][(e + 1) % 3])].push_back(t);
    return uses;
}

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
std::vector<std::vector<int>> walkShells(TriangleMesh& mesh, const std::map<EdgeKey, std::vector<int>>& uses)
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
                const std::vector<int>& users = uses.at(undirected(a, b));
                if (users.size() != 2) continue;  // open or non-manifold: no neighbour to agree with
                const int other = users[0] == shell[next] ? users[1] : users[0];
                if (reached[other]) continue;
                reached[other] = 1;
                if (runsFromTo(mesh.triangles[other], a, b)) turn(mesh.triangles[other]);
                shell.push_back(other);
            }
        }
        shells.push_back(std::move(shell));
    }
    return shells;
}

/// Merges vertices at equal positions (readers keep copies per face normal or texture seam) and
/// drops triangles that two of their corners then share, which bound nothing.
void weldEqualPositions(TriangleMesh& mesh)
{
    std::map<std::array<float, 3>, int> firstAt;
    std::vector<int> welded(mesh.positionsM.size());
    std::vector<Eigen::Vector3f> unique;
    for (size_t v = 0; v < mesh.positionsM.size(); ++v) {
        const Eigen::Vector3f& p = mesh.positionsM[v];
        const auto [it, isNew] = firstAt.try_emplace({p.x(), p.y(), p.z()}, static_cast<int>(unique.size()));
        if (isNew) unique.push_back(p);
        welded[v] = it->second;
    }
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
    const auto uses = edgeUses(mesh);
    for (const auto& [edge, users] : uses) topology.openEdges += (users.size() != 2);
    const auto shells = walkShells(mesh, uses);
    topology.shells = static_cast<int64_t>(shells.size());
    double sixV = 0.0;
    for (const auto& shell : shells) {
        const double sixShell = sixConeVolume(mesh, shell, vertexMean(mesh, shell));
        sixV += std::abs(sixShell);
        if (sixShell < 0.0)
            for (int t : shell) turn(mesh.triangles[t]);
    }
    topology.enclosedVolumeM3 = sixV / 6.0;
    for (size_t t = 0; t < asGiven.size(); ++t) topology.turnedTriangles += (mesh.triangles[t] != asGiven[t]);
    return topology;
}

}  // namespace spall
