#include <spall/fracture/Fracture.h>

#include <spall/voxel/Components.h>

#include <openvdb/tree/LeafManager.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace spall {

double linkRandom(uint64_t seed, const openvdb::Coord& ijk, int axis)
{
    // splitmix64 finaliser over a combination of the inputs.
    uint64_t z = seed * 0x9E3779B97F4A7C15ull ^ (uint64_t(uint32_t(ijk.x())) * 0xBF58476D1CE4E5B9ull) ^
                 (uint64_t(uint32_t(ijk.y())) * 0x94D049BB133111EBull) ^ (uint64_t(uint32_t(ijk.z())) << 21) ^
                 (uint64_t(axis) << 58);
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return double(z >> 11) * (1.0 / 9007199254740992.0);
}

namespace {

enum class EventKind : uint8_t { BreakLink, Weaken, BreakAnchor };

struct LinkEvent {
    openvdb::Coord ijk;
    EventKind kind;
    int8_t face;    ///< face for BreakLink, axis for Weaken
    int16_t charge; ///< for Weaken
};

/// The unit radius vector from the sample's dominant charge to x (zero when there is none).
Eigen::Vector3d waveDirection(const PressureSnapshot& pressure, const PressureSample& load, const Eigen::Vector3d& x)
{
    if (load.dominantCharge < 0) return Eigen::Vector3d::Zero();
    const Eigen::Vector3d r = x - pressure.chargePositionM(load.dominantWindow);
    const double n = r.norm();
    return n > 0 ? Eigen::Vector3d(r / n) : Eigen::Vector3d::Zero();
}

}  // namespace

LoadResult loadLinks(Body& body, DamageGrid* damage, const Material& material, const PressureSnapshot& pressure, double dtS,
                     const FractureSettings& settings)
{
    LoadResult result;
    if (settings.algorithm == FractureAlgorithm::None || pressure.empty()) return result;
    const double h = body.voxelSizeM;
    const Eigen::Matrix3d rot = body.orientation.toRotationMatrix();
    const Eigen::Matrix3d rotH = rot * h;  // world displacement per index step
    const double leafRadius = 0.5 * std::sqrt(3.0) * LinkLeaf::DIM * h;
    const bool davisonStevens = settings.algorithm == FractureAlgorithm::DavisonStevens;
    const double orientationFactor = settings.orientation ? material.orientationFactor : 0.0;
    const double weakening = settings.weakening ? material.weakeningFraction : 0.0;
    const double stressScale = material.damageStressScalePerPa > 0 ? material.damageStressScalePerPa : 1.0 / material.meanYieldPa;
    constexpr double kMaxDamage = 6.0;  // D*: six links per voxel
    // The least pressure that can change anything: a link's lowest possible limit (after
    // variation, orientation and weakening), or the damage threshold.
    const double leastEffectivePa =
        davisonStevens ? material.meanYieldPa
                       : std::min(material.meanYieldPa * (1.0 - material.yieldVariation) * (1.0 - orientationFactor) * (1.0 - weakening),
                                  material.meanYieldPa * (1.0 - material.yieldVariation));  // anchors

    openvdb::tree::LeafManager<const LinkTree> leaves(body.grid->constTree());
    std::vector<std::vector<LinkEvent>> events(leaves.leafCount());
    std::vector<char> skipped(leaves.leafCount(), 0);

    // Generate: a pure pass over leaves; each task writes only its own event list (and, for
    // Davison–Stevens, its own leaf of the damage grid).
    leaves.foreach ([&](const LinkLeaf& leaf, size_t n) {
        const Eigen::Vector3d originM = body.voxelWorldM(leaf.origin());
        const Eigen::Vector3d leafCentre = originM + rotH * Eigen::Vector3d::Constant(0.5 * (LinkLeaf::DIM - 1));
        // Skip the leaf when the pressure now, anywhere within its bounding sphere, stays below
        // the least effective limit: most of a body is either not reached yet or long passed.
        bool inside = false;
        double boundPa = 0.0;
        for (size_t w = 0; w < pressure.windows().size(); ++w) {
            const double d = (leafCentre - pressure.chargePositionM(w)).norm();
            if (d + leafRadius < pressure.innerM(w) || d - leafRadius > pressure.frontM(w)) continue;
            inside = true;
            boundPa += pressure.maxOverShellPa(w, d - leafRadius, d + leafRadius);
        }
        if (!inside || boundPa < leastEffectivePa) {
            skipped[n] = 1;
            return;
        }
        DamageTree::LeafNodeType* damageLeaf = damage ? damage->tree().probeLeaf(leaf.origin()) : nullptr;
        auto& out = events[n];
        for (auto it = leaf.cbeginValueOn(); it; ++it) {
            const openvdb::Coord ijk = it.getCoord();
            const int32_t bits = it.getValue();
            const openvdb::Coord local = ijk - leaf.origin();
            const Eigen::Vector3d x = originM + rotH * Eigen::Vector3d(local.x(), local.y(), local.z());
            if (bits & kAnchorBit) {
                const PressureSample load = pressure.sample(x);
                if (load.overpressurePa >= baseYieldLimit(material, settings.seed, ijk, 3))
                    out.push_back({ijk, EventKind::BreakAnchor, 0, 0});
            }
            if (davisonStevens) {
                // Rate form of Davison–Stevens (paper eq. 2.2, 3.2): dD/dt = B D* (exp(C s) - 1),
                // s = max(p - mean yield, 0); the paper's per-step B equals B dt here.
                if (!(bits & kAllLinks) || !damageLeaf) continue;
                const PressureSample load = pressure.sample(x);
                const double sigma = std::max(load.overpressurePa - material.meanYieldPa, 0.0);
                if (sigma <= 0.0) continue;
                const double before = damageLeaf->getValue(it.pos());
                const double rate = material.damageRatePerS * kMaxDamage * std::expm1(std::min(stressScale * sigma, 50.0));
                const double after = std::min(before + rate * dtS, kMaxDamage);
                damageLeaf->setValueOnly(it.pos(), static_cast<float>(after));
                int toBreak = static_cast<int>(std::floor(after)) - static_cast<int>(std::floor(before));
                if (toBreak <= 0) continue;
                // Break the intact links most aligned with the wave first (ties: face order).
                std::array<std::pair<double, int>, kFaceCount> order;
                int count = 0;
                const Eigen::Vector3d direction = waveDirection(pressure, load, x);
                for (int f = 0; f < kFaceCount; ++f) {
                    if (bits & (1 << f)) order[count++] = {-std::abs((rot * faceNormal(f)).dot(direction)), f};
                }
                // Insertion sort: at most six entries.
                for (int a = 1; a < count; ++a)
                    for (int b = a; b > 0 && order[b] < order[b - 1]; --b) std::swap(order[b], order[b - 1]);
                for (int k = 0; k < std::min(toBreak, count); ++k)
                    out.push_back({ijk, EventKind::BreakLink, static_cast<int8_t>(order[k].second), 0});
                continue;
            }
            for (int axis = 0; axis < 3; ++axis) {
                const int face = 2 * axis + 1;
                if (!(bits & (1 << face))) continue;
                const Eigen::Vector3d midpoint = x + 0.5 * rotH.col(axis);
                const PressureSample load = pressure.sample(midpoint);
                // Below the least limit any link can have, nothing can happen: skip the hash.
                if (load.overpressurePa < leastEffectivePa || load.overpressurePa <= 0.0) continue;
                double limit = baseYieldLimit(material, settings.seed, ijk, axis);
                if (orientationFactor > 0) limit *= 1.0 - orientationFactor * std::abs(rot.col(axis).dot(waveDirection(pressure, load, midpoint)));
                const int weakenedBy = weakenedByCharge(bits, axis);
                const bool weakenedEarlier = weakening > 0 && weakenedBy >= 0 && weakenedBy != load.dominantCharge;
                if (load.overpressurePa >= (weakenedEarlier ? (1.0 - weakening) * limit : limit)) {
                    out.push_back({ijk, EventKind::BreakLink, static_cast<int8_t>(face), 0});
                } else if (weakening > 0 && weakenedBy < 0 && load.overpressurePa >= (1.0 - weakening) * limit) {
                    out.push_back({ijk, EventKind::Weaken, static_cast<int8_t>(axis), static_cast<int16_t>(load.dominantCharge)});
                }
            }
        }
    });

    // Apply in leaf order: the result does not depend on how the pass was scheduled.
    auto acc = body.grid->getAccessor();
    for (size_t n = 0; n < events.size(); ++n) {
        result.skippedLeaves += skipped[n];
        for (const LinkEvent& e : events[n]) {
            switch (e.kind) {
            case EventKind::BreakLink: result.brokenLinks += breakLink(acc, e.ijk, e.face); break;
            case EventKind::Weaken: {
                const int32_t bits = acc.getValue(e.ijk);
                const int shift = kWeakenedShift + 8 * e.face;
                acc.setValueOn(e.ijk, (bits & ~(0xff << shift)) | (((e.charge + 1) & 0xff) << shift));
                break;
            }
            case EventKind::BreakAnchor:
                acc.setValueOn(e.ijk, acc.getValue(e.ijk) & ~kAnchorBit);
                ++result.brokenAnchors;
                break;
            }
        }
    }
    body.linkCount -= result.brokenLinks;
    if (result.brokenAnchors > 0) body.anchored = hasAnchoredVoxel(*body.grid);
    return result;
}

std::vector<SplitPart> splitBody(const Body& body, const DamageGrid* damage)
{
    const ComponentLabels labels = labelComponents(*body.grid);
    std::vector<SplitPart> parts;
    if (labels.componentCount <= 1) return parts;
    std::vector<LinkGrid::Ptr> grids = splitByLabels(*body.grid, labels);

    std::vector<DamageGrid::Ptr> damageParts(grids.size());
    if (damage) {
        for (auto& d : damageParts) {
            d = DamageGrid::create(0.0f);
            d->setTransform(damage->transform().copy());
            d->setName(damage->getName());
        }
        for (size_t n = 0; n < labels.leaves.size(); ++n) {
            const LinkLeaf& leaf = *labels.leaves[n];
            const auto* source = damage->constTree().probeConstLeaf(leaf.origin());
            for (auto it = leaf.cbeginValueOn(); it; ++it) {
                const uint32_t label = labels.labelOfSlot[n * LinkLeaf::SIZE + it.pos()];
                damageParts[label]->tree().touchLeaf(leaf.origin())->setValueOn(it.pos(), source ? source->getValue(it.pos()) : 0.0f);
            }
        }
    }

    const Eigen::Matrix3d rot = body.orientation.toRotationMatrix();
    parts.reserve(grids.size());
    for (size_t i = 0; i < grids.size(); ++i) {
        SplitPart part;
        Body& child = part.body;
        child.parentId = body.id;
        child.materialIndex = body.materialIndex;
        child.grid = grids[i];
        child.voxelSizeM = body.voxelSizeM;
        child.densityKgM3 = body.densityKgM3;
        refreshDerivedData(child);
        child.orientation = body.orientation;
        // The parent's rigid velocity field at the child's centre of mass (paper 4.1).
        const Eigen::Vector3d offset = rot * (child.mass.centreOfMassLocalM - body.mass.centreOfMassLocalM);
        child.positionM = body.positionM + offset;
        child.angularVelocityRadS = body.angularVelocityRadS;
        child.linearVelocityMS = body.linearVelocityMS + body.angularVelocityRadS.cross(offset);
        part.damage = damageParts[i];
        parts.push_back(std::move(part));
    }
    return parts;
}

}  // namespace spall
