#include <spall/fracture/Fracture.h>

#include <spall/core/Hash.h>
#include <spall/voxel/Components.h>

#include <openvdb/tree/LeafManager.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace spall {

double linkRandom(uint64_t seed, const openvdb::Coord& ijk, int axis)
{
    // splitmix64 over a combination of the inputs.
    const uint64_t z = seed * 0x9E3779B97F4A7C15ull ^ (uint64_t(uint32_t(ijk.x())) * 0xBF58476D1CE4E5B9ull) ^
                       (uint64_t(uint32_t(ijk.y())) * 0x94D049BB133111EBull) ^ (uint64_t(uint32_t(ijk.z())) << 21) ^
                       (uint64_t(axis) << 58);
    return unitInterval(splitmix64(z));
}

namespace {

// Generate, apply, split (after NVIDIA Blast): the rules below generate events in a pure pass
// over leaves; applyLinkEvents applies them in leaf order; the caller splits.

enum class EventKind : uint8_t { BreakLink, Weaken, BreakAnchor, SetDamage };

struct LinkEvent {
    openvdb::Coord ijk;
    EventKind kind;
    int8_t face = 0;     ///< face for BreakLink, axis for Weaken
    int16_t charge = 0;  ///< for Weaken
    float damage = 0;    ///< for SetDamage
};

constexpr double kMaxDamage = 6.0;  // Davison–Stevens D*: six links per voxel

/// The unit radius vector from the sample's dominant charge to x (zero when there is none).
Eigen::Vector3d waveDirection(const PressureSnapshot& pressure, const PressureSample& load, const Eigen::Vector3d& x)
{
    if (load.dominantCharge < 0) return Eigen::Vector3d::Zero();
    const Eigen::Vector3d r = x - pressure.chargePositionM(load.dominantWindow);
    const double n = r.norm();
    return n > 0 ? Eigen::Vector3d(r / n) : Eigen::Vector3d::Zero();
}

/// The paper's rules (section 3.3) for one body in one step: what each needs, and one event
/// generator per rule. Pure: generating changes nothing.
class LinkRules {
public:
    LinkRules(const Body& body, const Material& material, const PressureSnapshot& pressure, const FractureSettings& settings, uint64_t seed,
              double dtS)
        : mBody(body), mMaterial(material), mPressure(pressure), mSettings(settings), mSeed(seed), mDtS(dtS),
          mRotation(body.motion.orientation.toRotationMatrix()), mIndexStepM(mRotation * body.voxelSizeM),
          mLeafRadiusM(0.5 * std::sqrt(3.0) * LinkLeaf::DIM * body.voxelSizeM),
          mOrientationFactor(settings.orientation ? material.orientationFactor : 0.0),
          mWeakening(settings.weakening ? material.weakeningFraction : 0.0),
          mStressScalePerPa(material.damageStressScalePerPa > 0 ? material.damageStressScalePerPa : 1.0 / material.meanYieldPa)
    {
        // The least pressure that can change anything: a link's lowest possible limit (after
        // variation, orientation and weakening), or the damage threshold.
        mLeastEffectivePa = davisonStevens() ? material.meanYieldPa
                                             : std::min(material.meanYieldPa * (1.0 - material.yieldVariation) * (1.0 - mOrientationFactor) *
                                                            (1.0 - mWeakening),
                                                        material.meanYieldPa * (1.0 - material.yieldVariation));  // anchors
    }

    /// The cull every rule shares: whether the pressure now, anywhere within the leaf's bounding
    /// sphere, can reach the least effective limit (most of a body is either not reached yet or
    /// long passed).
    bool leafCanChange(const LinkLeaf& leaf) const
    {
        const Eigen::Vector3d leafCentre = mBody.voxelWorldM(leaf.origin()) + mIndexStepM * Eigen::Vector3d::Constant(0.5 * (LinkLeaf::DIM - 1));
        bool inside = false;
        double boundPa = 0.0;
        for (size_t w = 0; w < mPressure.windows().size(); ++w) {
            const double d = (leafCentre - mPressure.chargePositionM(w)).norm();
            if (d + mLeafRadiusM < mPressure.innerM(w) || d - mLeafRadiusM > mPressure.frontM(w)) continue;
            inside = true;
            boundPa += mPressure.maxOverShellPa(w, d - mLeafRadiusM, d + mLeafRadiusM);
        }
        return inside && boundPa >= mLeastEffectivePa;
    }

    /// Every event of the leaf's voxels: the anchor rule, then the chosen link rule.
    void leafEvents(const LinkLeaf& leaf, const DamageGrid* damage, std::vector<LinkEvent>& out) const
    {
        const Eigen::Vector3d originM = mBody.voxelWorldM(leaf.origin());
        const auto* damageLeaf = damage ? damage->constTree().probeConstLeaf(leaf.origin()) : nullptr;
        for (auto it = leaf.cbeginValueOn(); it; ++it) {
            const openvdb::Coord ijk = it.getCoord();
            const int32_t bits = it.getValue();
            const openvdb::Coord local = ijk - leaf.origin();
            const Eigen::Vector3d x = originM + mIndexStepM * Eigen::Vector3d(local.x(), local.y(), local.z());
            if (bits & kAnchorBit) anchorEvents(ijk, x, out);
            if (davisonStevens()) {
                if ((bits & kAllLinks) && damageLeaf) damageEvents(ijk, bits, x, damageLeaf->getValue(it.pos()), out);
            } else {
                yieldLimitEvents(ijk, bits, x, out);
            }
        }
    }

private:
    bool davisonStevens() const { return mSettings.algorithm == FractureAlgorithm::DavisonStevens; }

    /// An anchor breaks like a link, at its own hashed limit.
    void anchorEvents(const openvdb::Coord& ijk, const Eigen::Vector3d& x, std::vector<LinkEvent>& out) const
    {
        if (mPressure.sample(x).overpressurePa >= baseYieldLimit(mMaterial, mSeed, ijk, 3))
            out.push_back({ijk, EventKind::BreakAnchor});
    }

    /// Rules 1-3: the +x, +y, +z links of the voxel against their variable limits (1), lowered by
    /// the angle to the wave (3) and, for a link an earlier charge loaded, by weakening (2).
    void yieldLimitEvents(const openvdb::Coord& ijk, int32_t bits, const Eigen::Vector3d& x, std::vector<LinkEvent>& out) const
    {
        for (int axis = 0; axis < 3; ++axis) {
            const int face = 2 * axis + 1;
            if (!(bits & (1 << face))) continue;
            const Eigen::Vector3d midpoint = x + 0.5 * mIndexStepM.col(axis);
            const PressureSample load = mPressure.sample(midpoint);
            // Below the least limit any link can have, nothing can happen: skip the hash.
            if (load.overpressurePa < mLeastEffectivePa || load.overpressurePa <= 0.0) continue;
            double limit = baseYieldLimit(mMaterial, mSeed, ijk, axis);
            if (mOrientationFactor > 0)
                limit *= 1.0 - mOrientationFactor * std::abs(mRotation.col(axis).dot(waveDirection(mPressure, load, midpoint)));
            const int weakenedBy = weakenedByCharge(bits, axis);
            const bool weakenedEarlier = mWeakening > 0 && weakenedBy >= 0 && weakenedBy != load.dominantCharge;
            if (load.overpressurePa >= (weakenedEarlier ? (1.0 - mWeakening) * limit : limit)) {
                out.push_back({ijk, EventKind::BreakLink, static_cast<int8_t>(face)});
            } else if (mWeakening > 0 && weakenedBy < 0 && load.overpressurePa >= (1.0 - mWeakening) * limit) {
                out.push_back({ijk, EventKind::Weaken, static_cast<int8_t>(axis), static_cast<int16_t>(load.dominantCharge)});
            }
        }
    }

    /// Rule 4, Davison–Stevens in rate form (paper eq. 2.2, 3.2): dD/dt = B D* (exp(C s) - 1),
    /// s = max(p - mean yield, 0); the paper's per-step B equals B dt here. Each whole unit of
    /// damage breaks the intact link most aligned with the wave (ties: face order).
    void damageEvents(const openvdb::Coord& ijk, int32_t bits, const Eigen::Vector3d& x, double before, std::vector<LinkEvent>& out) const
    {
        const PressureSample load = mPressure.sample(x);
        const double sigma = std::max(load.overpressurePa - mMaterial.meanYieldPa, 0.0);
        if (sigma <= 0.0) return;
        const double rate = mMaterial.damageRatePerS * kMaxDamage * std::expm1(std::min(mStressScalePerPa * sigma, 50.0));
        const double after = std::min(before + rate * mDtS, kMaxDamage);
        out.push_back({ijk, EventKind::SetDamage, 0, 0, static_cast<float>(after)});
        const int toBreak = static_cast<int>(std::floor(after)) - static_cast<int>(std::floor(before));
        if (toBreak <= 0) return;
        std::array<std::pair<double, int>, kFaceCount> order;
        int count = 0;
        const Eigen::Vector3d direction = waveDirection(mPressure, load, x);
        for (int f = 0; f < kFaceCount; ++f)
            if (bits & (1 << f)) order[count++] = {-std::abs((mRotation * faceNormal(f)).dot(direction)), f};
        // Insertion sort: at most six entries.
        for (int a = 1; a < count; ++a)
            for (int b = a; b > 0 && order[b] < order[b - 1]; --b) std::swap(order[b], order[b - 1]);
        for (int k = 0; k < std::min(toBreak, count); ++k) out.push_back({ijk, EventKind::BreakLink, static_cast<int8_t>(order[k].second)});
    }

    const Body& mBody;
    const Material& mMaterial;
    const PressureSnapshot& mPressure;
    const FractureSettings& mSettings;
    uint64_t mSeed;
    double mDtS;
    Eigen::Matrix3d mRotation;
    Eigen::Matrix3d mIndexStepM;  ///< world displacement per index step
    double mLeafRadiusM;
    double mOrientationFactor, mWeakening, mStressScalePerPa;
    double mLeastEffectivePa = 0;
};

/// Applies the events in leaf order (the result does not depend on how they were generated);
/// the body's link count and anchored flag follow.
LoadResult applyLinkEvents(Body& body, const std::vector<std::vector<LinkEvent>>& events)
{
    LoadResult result;
    auto acc = body.grid->getAccessor();
    for (const std::vector<LinkEvent>& leafEvents : events) {
        for (const LinkEvent& e : leafEvents) {
            switch (e.kind) {
            case EventKind::BreakLink: result.brokenLinks += breakLink(acc, e.ijk, e.face); break;
            case EventKind::Weaken: acc.setValueOn(e.ijk, withWeakenedByCharge(acc.getValue(e.ijk), e.face, e.charge)); break;
            case EventKind::BreakAnchor:
                acc.setValueOn(e.ijk, acc.getValue(e.ijk) & ~kAnchorBit);
                ++result.brokenAnchors;
                break;
            case EventKind::SetDamage: body.damage->tree().setValueOnly(e.ijk, e.damage); break;
            }
        }
    }
    body.linkCount -= result.brokenLinks;
    if (result.brokenAnchors > 0) body.anchored = hasAnchoredVoxel(*body.grid);
    return result;
}

}  // namespace

LoadResult loadLinks(Body& body, const Material& material, const PressureSnapshot& pressure, double dtS,
                     const FractureSettings& settings, uint64_t seed)
{
    if (settings.algorithm == FractureAlgorithm::None || pressure.empty()) return {};
    const LinkRules rules(body, material, pressure, settings, seed, dtS);
    openvdb::tree::LeafManager<const LinkTree> leaves(body.grid->constTree());
    std::vector<std::vector<LinkEvent>> events(leaves.leafCount());
    std::vector<char> skipped(leaves.leafCount(), 0);
    // Generate: each task writes only its own leaf's events.
    leaves.foreach ([&](const LinkLeaf& leaf, size_t n) {
        if (rules.leafCanChange(leaf))
            rules.leafEvents(leaf, body.damage.get(), events[n]);
        else
            skipped[n] = 1;
    });
    LoadResult result = applyLinkEvents(body, events);
    result.skippedLeaves = std::count(skipped.begin(), skipped.end(), 1);
    return result;
}

DamageGrid::Ptr zeroDamageLike(const LinkGrid& grid)
{
    auto damage = DamageGrid::create(0.0f);
    damage->setTransform(grid.transform().copy());
    copyActiveTopology(damage->tree(), grid.constTree(), 0.0f);
    return damage;
}

namespace {

/// A per-voxel grid of the parent (its damage), cut along the same labels as its voxels.
template <typename GridT>
std::vector<typename GridT::Ptr> splitAlongLabels(const GridT& values, const ComponentLabels& labels, size_t partCount)
{
    using ValueT = typename GridT::ValueType;
    const ValueT zero = openvdb::zeroVal<ValueT>();
    std::vector<typename GridT::Ptr> parts(partCount);
    for (auto& part : parts) {
        part = GridT::create(zero);
        part->setTransform(values.transform().copy());
        part->setName(values.getName());
    }
    for (size_t n = 0; n < labels.leaves.size(); ++n) {
        const LinkLeaf& leaf = *labels.leaves[n];
        const auto* source = values.constTree().probeConstLeaf(leaf.origin());
        for (auto it = leaf.cbeginValueOn(); it; ++it) {
            const uint32_t label = labels.labelOfSlot[n * LinkLeaf::SIZE + it.pos()];
            parts[label]->tree().touchLeaf(leaf.origin())->setValueOn(it.pos(), source ? source->getValue(it.pos()) : zero);
        }
    }
    return parts;
}

}  // namespace

std::vector<Body> splitBody(const Body& body)
{
    const ComponentLabels labels = labelComponents(*body.grid);
    std::vector<Body> parts;
    if (labels.componentCount <= 1) return parts;
    std::vector<LinkGrid::Ptr> grids = splitByLabels(*body.grid, labels);
    std::vector<DamageGrid::Ptr> damage(grids.size());
    if (body.damage) damage = splitAlongLabels(*body.damage, labels, grids.size());
    std::vector<LinkDamageGrid::Ptr> linkDamage(grids.size());
    if (body.linkDamage) linkDamage = splitAlongLabels(*body.linkDamage, labels, grids.size());
    const Eigen::Matrix3d rot = body.motion.orientation.toRotationMatrix();
    parts.reserve(grids.size());
    for (size_t i = 0; i < grids.size(); ++i) {
        Body child;
        child.parentId = body.id;
        child.materialIndex = body.materialIndex;
        child.grid = grids[i];
        child.damage = damage[i];
        child.linkDamage = linkDamage[i];
        child.voxelSizeM = body.voxelSizeM;
        child.densityKgM3 = body.densityKgM3;
        refreshDerivedData(child);
        child.motion.orientation = body.motion.orientation;
        // The parent's rigid velocity field at the child's centre of mass (paper 4.1).
        const Eigen::Vector3d offset = rot * (child.mass.centreOfMassLocalM - body.mass.centreOfMassLocalM);
        child.motion.positionM = body.motion.positionM + offset;
        child.motion.angularVelocityRadS = body.motion.angularVelocityRadS;
        child.motion.linearVelocityMS = body.motion.linearVelocityMS + body.motion.angularVelocityRadS.cross(offset);
        child.motion.survivedImpactMS = body.motion.survivedImpactMS;
        parts.push_back(std::move(child));
    }
    return parts;
}

}  // namespace spall
