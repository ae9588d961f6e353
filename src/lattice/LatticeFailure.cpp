// How a lattice's bonds fail: the failure index as an equivalent stretch (tension cut-off joined
// to shear, Mohr–Coulomb in compression), the damage it drives on the softening line (crack band)
// or at a rate (Davison–Stevens), the strain-rate law's effect on the line's peak, and crushing
// (Hoek–Brown in compression, its own softening line). What the bond pass calls for every bond is
// inline in LatticeBondLaws.h; the members here report it and set it.
#include "LatticeBondLaws.h"

namespace spall {

double Lattice::bondDamage(size_t b) const
{
    return bond_laws::bondDamage(state.bondHistory[b], strengthOf(b), mModel.damageLaw);
}

double Lattice::residualStrengthFraction(size_t b) const
{
    const double damage = bondDamage(b);
    if (damage >= 1.0) return 0.0;
    const double u0 = softeningLineM(b).first;
    return (1.0 - damage) * std::max(state.bondHistory[b].maxEquivalentStretchM, u0) / u0;
}

bool Lattice::brokenAtHandOff(size_t b) const
{
    return residualStrengthFraction(b) < mModel.handOffResidualStrength;
}

double Lattice::crushingDamage(size_t b) const
{
    return bond_laws::crushingDamage(state.bondHistory[b], strengthOf(b));
}

bool Lattice::canCrush() const
{
    return mModel.stiffness.strength[0].compressiveStrengthPa > 0.0 || mModel.stiffness.strength[1].compressiveStrengthPa > 0.0;
}

std::pair<double, double> Lattice::softeningLineM(size_t b) const
{
    return bond_laws::softeningLineM(state.bondHistory[b], strengthOf(b));
}

double Lattice::softeningDamage(size_t b) const
{
    return bond_laws::softeningDamage(state.bondHistory[b], strengthOf(b));
}

void Lattice::startDamaged(size_t b, double damage)
{
    // Below 1: the link the bond stands for is intact, and float storage may have rounded it up.
    damage = std::min(damage, kLargestIntactDamage);
    BondHistory& history = state.bondHistory[b];
    const auto [u0, uf] = softeningLineM(b);
    // softeningDamage inverted: (1 − D) κ / u0 = (uf − κ) / (uf − u0) gives
    // κ = u0 uf / ((1 − D)(uf − u0) + u0). A bond that breaks at its peak has no such line.
    history.maxEquivalentStretchM = snapsAtPeak(b) ? u0 : u0 * uf / ((1.0 - damage) * (uf - u0) + u0);
    history.rateDamage = damage;
}

void Lattice::breakBond(size_t b)
{
    BondHistory& history = state.bondHistory[b];
    const auto [u0, uf] = softeningLineM(b);
    // Past both ends of its softening line (a bond that snaps at its peak breaks just past it).
    history.maxEquivalentStretchM = std::max({history.maxEquivalentStretchM, uf, u0}) * (1.0 + 1e-9);
    history.rateDamage = 1.0;
    mBroken[b] = 1;
    mPiecesStale = true;
}

bool Lattice::snapsAtPeak(size_t b) const
{
    return bond_laws::snapsAtPeak(strengthOf(b));
}

double Lattice::equivalentStretchM(size_t b) const
{
    const LatticeBond& bond = mModel.bonds[b];
    return equivalentStretchM(b, strainOf(bond), (state.positionM[bond.high] - state.positionM[bond.low]).norm(), bondDamage(b));
}

void Lattice::computeFailureTerms()
{
    const LatticeStiffness& k = mModel.stiffness;
    const double faceAreaM2 = mModel.spacingM * mModel.spacingM;
    for (size_t strengthClass = 0; strengthClass < 2; ++strengthClass)
        for (size_t axis = 0; axis < 3; ++axis) {
            const LatticeStiffness::Strength& strength = k.strength[strengthClass];
            LatticeModel::FailureTerms& terms = mModel.failureTerms[strengthClass][axis];
            terms.peakStretchM = strength.peakStretchM;
            terms.tensionIndexPerM = 1.0 / strength.peakStretchM;
            terms.shearIndexPerM = k.shearNPerM[axis] / (faceAreaM2 * strength.shearStrengthPa);
            terms.normalIndexPerM = k.normalNPerM[axis] / (faceAreaM2 * strength.shearStrengthPa);
            terms.indexPerPa = 1.0 / strength.shearStrengthPa;
            terms.frictionCoefficient = strength.frictionCoefficient;
        }
}

void Lattice::followStrengthRate(BondHistory& history, double increaseM, double strainRatePerS) const
{
    const StrengthRateLaw law = mModel.stiffness.strengthRateLaw;
    if (law == StrengthRateLaw::None) return;
    history.rateWeightedStretchM += increaseM / dynamicIncreaseFactor(law, strainRatePerS);
    history.strengthFactor = history.maxEquivalentStretchM / history.rateWeightedStretchM;
}

double Lattice::rateDamageAfter(size_t b, double equivalentStretchNowM, double dtS) const
{
    const BondHistory& history = state.bondHistory[b];
    const double onLine = softeningDamage(b);
    // Past the softening line's end the crack is open: broken, as in the crack band.
    if (onLine >= 1.0) return 1.0;
    // Stretches as stresses in units of the bond's strength: its own (its equivalent stretch on
    // its damaged spring) and what the softening line allows at its damage driver.
    const double peakM = softeningLineM(b).first, kappa = history.maxEquivalentStretchM;
    const double stress = (1.0 - history.rateDamage) * equivalentStretchNowM / peakM;
    const double allowed = kappa <= peakM ? 1.0 : (1.0 - onLine) * kappa / peakM;
    const double excess = stress - allowed;
    if (excess <= 0.0) return history.rateDamage;
    // dD/dt = B [exp(C σx) − 1] with B = (B ε0) / ε0 at the bond's own peak strain (RateDamage.h);
    // past exp(50) the step breaks the bond anyway. A step never takes the bond below what
    // the line allows: the excess is what the law relaxes, not a target to overshoot.
    const DavisonStevensConstants& law = mModel.stiffness.davisonStevens;
    const double peakStrain = peakM / mModel.spacingM;
    const double rate = law.rateTimesPeakStrainPerS / peakStrain * std::expm1(std::min(law.excessExponent * excess, 50.0));
    const double relaxed = 1.0 - allowed * peakM / equivalentStretchNowM;
    return std::min({1.0, relaxed, history.rateDamage + rate * dtS});
}

}  // namespace spall
