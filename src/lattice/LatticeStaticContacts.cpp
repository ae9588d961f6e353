// A lattice against the static world: the ground plane its particles may not sink into (unless
// still bonded to their ground point) and the colliders they may not pass through, each with its
// Coulomb friction.
#include <spall/lattice/Lattice.h>

#include <algorithm>

namespace spall {

bool Lattice::bondedToGround(size_t p) const
{
    return p < mModel.groundBond.size() && mModel.groundBond[p] >= 0 && bondDamage(size_t(mModel.groundBond[p])) < 1.0;
}

void Lattice::keepOutOf(const StaticWorld& supports)
{
    // The particle's centre may come within a quarter edge of a box's faces (its cube sinking in
    // by up to a quarter edge); deeper, it goes back out across the nearest face.
    const double allowedM = 0.25 * mModel.spacingM;
    mModel.keptOut.clear();
    for (size_t i = 0; i < supports.boxes.size(); ++i) {
        const ObstacleBox& box = supports.boxes[i];
        LatticeModel::KeptOut kept{box.orientation.toRotationMatrix().transpose(), box.centreM, box.halfExtentM + Eigen::Vector3d::Constant(allowedM), {},
                                   i < supports.friction.size() ? supports.friction[i] : 0.0};
        const ObstacleBox grown{box.centreM, kept.reachM, box.orientation};
        for (const Eigen::Vector3d& corner : cornersOf(grown)) kept.boundsM.extend(corner);
        mModel.keptOut.push_back(kept);
    }
}

void Lattice::keepOutOfColliders(size_t p)
{
    for (const LatticeModel::KeptOut& box : mModel.keptOut) {
        if (!box.boundsM.contains(state.positionM[p])) continue;
        const Eigen::Vector3d local = box.toBox * (state.positionM[p] - box.centreM);
        const Eigen::Vector3d depth = box.reachM - local.cwiseAbs();
        if ((depth.array() <= 0.0).any()) continue;
        int axis = 0;
        depth.minCoeff(&axis);
        const Eigen::Vector3d outward = box.toBox.row(axis).transpose() * (local[axis] >= 0.0 ? 1.0 : -1.0);
        pushOut(p, outward, depth[axis], box.friction);
    }
}

void Lattice::keepAboveGround(size_t p)
{
    const double depth = mModel.ground.offsetM + 0.5 * mModel.spacingM - mModel.ground.normal.dot(state.positionM[p]);
    if (depth > 0.0) pushOut(p, mModel.ground.normal, depth, mModel.ground.friction);
}

void Lattice::pushOut(size_t p, const Eigen::Vector3d& outward, double depthM, double friction)
{
    state.positionM[p] += depthM * outward;
    Eigen::Vector3d& v = state.velocityMS[p];
    const double into = outward.dot(v);
    if (into >= 0.0) return;
    v -= into * outward;
    const Eigen::Vector3d sliding = v - outward.dot(v) * outward;
    const double slidingMS = sliding.norm();
    if (slidingMS > 0.0) v -= std::min(1.0, friction * -into / slidingMS) * sliding;
}

}  // namespace spall
