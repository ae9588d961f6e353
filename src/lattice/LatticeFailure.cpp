// How a lattice's bonds fail: the failure index as an equivalent stretch (tension cut-off joined
// to shear, Mohr–Coulomb in compression), the damage it drives on the softening line (crack band)
// or at a rate (Davison–Stevens), the strain-rate law's effect on the line's peak, and crushing
// (Hoek–Brown in compression, its own softening line).
#include <spall/lattice/Lattice.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace spall {

namespace {

/// The shear traction over the shear strength: |(k_b d_b, k_c d_c)| / (h² c) across axis a.
double shearIndexOf(const Eigen::Vector3d& perM, const Eigen::Vector3d& displacementM, int a)
{
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    // Equal factors (isotropic): one product, as the golden states were recorded with.
    if (perM[b] == perM[c]) return perM[b] * std::sqrt(std::max(0.0, displacementM.squaredNorm() - displacementM[a] * displacementM[a]));
    return std::hypot(perM[b] * displacementM[b], perM[c] * displacementM[c]);
}

/// Damage on a linear softening line from u0 to uf at the driver κ: the secant stiffness
/// (1 − D) κ / u0 = (uf − κ) / (uf − u0) (Bažant & Oh 1983's crack band, linear).
double lineDamage(double kappa, double u0, double uf)
{
    if (kappa <= u0) return 0.0;
    if (kappa >= uf) return 1.0;
    return 1.0 - (u0 / kappa) * (uf - kappa) / (uf - u0);
}

}  // namespace

double Lattice::bondDamage(size_t b) const
{
    const double cracked = crackingDamage(b), crushed = crushingDamage(b);
    // Without crushing, exactly D_t (1 − (1 − D_t) need not round back to it).
    return crushed == 0.0 ? cracked : 1.0 - (1.0 - cracked) * (1.0 - crushed);
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

double Lattice::crackingDamage(size_t b) const
{
    return mModel.damageLaw == LatticeDamageLaw::DavisonStevens ? state.bondHistory[b].rateDamage : softeningDamage(b);
}

double Lattice::crushingDamage(size_t b) const
{
    const BondHistory& history = state.bondHistory[b];
    const LatticeStiffness::Strength& strength = mModel.stiffness.strength[mModel.bonds[b].strengthClass];
    if (history.maxCrushingShorteningM <= 0.0) return 0.0;
    // The strength scale (scatter, a weak joint) scales crushing as it scales cracking.
    return lineDamage(history.maxCrushingShorteningM, history.strengthScale * strength.crushingPeakShorteningM,
                      strength.crushingEndShorteningM / history.strengthScale);
}

bool Lattice::canCrush() const
{
    return mModel.stiffness.strength[0].compressiveStrengthPa > 0.0 || mModel.stiffness.strength[1].compressiveStrengthPa > 0.0;
}

double Lattice::confinementPa(uint32_t p, int a) const
{
    double leastCompressionPa = std::numeric_limits<double>::infinity();
    for (const int lateral : {(a + 1) % 3, (a + 2) % 3}) {
        double sumPa = 0.0;
        for (const int face : {2 * lateral, 2 * lateral + 1})
            if (const int32_t b = mModel.bondAcross[p][face]; b >= 0) sumPa += mBondNormalStressPa[size_t(b)];
        leastCompressionPa = std::min(leastCompressionPa, -sumPa * mModel.inverseBondCount[p][lateral]);
    }
    return std::max(0.0, leastCompressionPa);
}

double Lattice::crushingShorteningM(size_t b, double normalM) const
{
    const LatticeBond& bond = mModel.bonds[b];
    const LatticeStiffness::Strength& strength = mModel.stiffness.strength[bond.strengthClass];
    if (strength.compressiveStrengthPa <= 0.0 || bond.pinned || normalM >= 0.0) return 0.0;
    const int a = bond.axis;
    const double compressionPa =
        -(mModel.stiffness.normalModulusPa[size_t(a)] * normalM / mModel.spacingM + 0.5 * (mUncrushedLambdaTracePa[bond.low] + mUncrushedLambdaTracePa[bond.high]));
    if (compressionPa <= 0.0) return 0.0;
    // Confinement only strengthens (σ1 ≥ fc for σ3 ≥ 0): a compression that could not pass the
    // largest shortening so far even unconfined grows nothing, and needs no confinement read.
    const double unconfinedM = compressionPa / strength.compressiveStrengthPa * strength.crushingPeakShorteningM;
    if (unconfinedM <= state.bondHistory[b].maxCrushingShorteningM) return unconfinedM;
    const double fc = strength.compressiveStrengthPa, lateralPa = 0.5 * (confinementPa(bond.low, a) + confinementPa(bond.high, a));
    const double strengthPa = lateralPa + fc * std::sqrt(strength.confinementM * lateralPa / fc + 1.0);
    return compressionPa / strengthPa * strength.crushingPeakShorteningM;
}

std::pair<double, double> Lattice::softeningLineM(size_t b) const
{
    const BondHistory& history = state.bondHistory[b];
    const double scale = history.strengthScale * history.strengthFactor;
    const LatticeStiffness::Strength& strength = mModel.stiffness.strength[mModel.bonds[b].strengthClass];
    return {scale * strength.peakStretchM, strength.zeroTractionStretchM / scale};
}

double Lattice::softeningDamage(size_t b) const
{
    const auto [u0, uf] = softeningLineM(b);
    const double kappa = state.bondHistory[b].maxEquivalentStretchM;
    // A bond too large to soften breaks at its peak, whatever its strength scale.
    if (kappa > u0 && snapsAtPeak(b)) return 1.0;
    return lineDamage(kappa, u0, uf);
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
    mPiecesStale = true;
}

bool Lattice::snapsAtPeak(size_t b) const
{
    const LatticeStiffness::Strength& strength = mModel.stiffness.strength[mModel.bonds[b].strengthClass];
    return strength.zeroTractionStretchM <= strength.peakStretchM;
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

double Lattice::equivalentStretchM(size_t b, const BondStrain& strain, double lengthM, double damage) const
{
    const LatticeBond& bond = mModel.bonds[b];
    const int a = bond.axis;
    const LatticeModel::FailureTerms& terms = mModel.failureTerms[bond.strengthClass][size_t(a)];
    // The shear displacement: across the bond's axis in its half-way frame.
    const double normalM = strain.displacementM[a];
    const double shearIndex = shearIndexOf(terms.shearIndexPerM, strain.displacementM, a);
    // The stretch at the face's most stretched corner: the moment the bond carries, (1 − D) of
    // its bending stiffness times θ, opens one edge by (1 − D) θ h/2 per axis across it, so the
    // outermost bonds of a bent member see the strain of its surface, E κ t/2, as a continuum
    // would (the parallel bond's σ = F/A + |M| R/I, Potyondy & Cundall 2004), not that of their
    // centres, t/2 − h/2 from the neutral axis. As the bond softens its moment goes, and its
    // opening alone carries it to the end of the softening line, so it still dissipates Gf.
    const Eigen::Vector3d& rotation = strain.rotationRad;
    const double bendingStretchM = 0.5 * mModel.spacingM * (1.0 - damage) * (std::abs(rotation[(a + 1) % 3]) + std::abs(rotation[(a + 2) % 3]));
    const double stretchM = bond.pinned ? 0.0 : lengthM - mModel.spacingM + bendingStretchM;  // a pin fails in shear
    double index = 0.0;
    if (stretchM >= 0.0) {
        const double tensionIndex = stretchM * terms.tensionIndexPerM;
        index = std::sqrt(tensionIndex * tensionIndex + shearIndex * shearIndex);
    } else {
        // The compression across the bond, over the shear strength: its spring's and its
        // particles' volumetric share, as the last force pass left them (a substep behind; a
        // function of the saved state).
        const double normalIndex =
            terms.normalIndexPerM * normalM + terms.indexPerPa * (mVolumetricStressShare[bond.low][a] + mVolumetricStressShare[bond.high][a]);
        index = std::max(0.0, shearIndex - terms.frictionCoefficient * std::max(0.0, -normalIndex));
    }
    return index * terms.peakStretchM;
}

void Lattice::followStrengthRate(BondHistory& history, double increaseM, double strainRatePerS) const
{
    const StrengthRateLaw law = mModel.stiffness.strengthRateLaw;
    if (law == StrengthRateLaw::None) return;
    history.rateWeightedStretchM += increaseM / dynamicIncreaseFactor(law, strainRatePerS);
    history.strengthFactor = history.maxEquivalentStretchM / history.rateWeightedStretchM;
}

bool Lattice::growBondDamage(size_t b, double equivalentStretchNowM, double crushingShorteningNowM, double strainRatePerS, double dtS)
{
    BondHistory& history = state.bondHistory[b];
    const bool crushing = crushingShorteningNowM > history.maxCrushingShorteningM;
    if (crushing) history.maxCrushingShorteningM = crushingShorteningNowM;
    const double increaseM = equivalentStretchNowM - history.maxEquivalentStretchM;
    if (increaseM > 0.0) {
        const bool undamaged = history.maxEquivalentStretchM <= softeningLineM(b).first;
        history.maxEquivalentStretchM += increaseM;
        if (undamaged) followStrengthRate(history, increaseM, strainRatePerS);
    }
    if (mModel.damageLaw == LatticeDamageLaw::DavisonStevens) {
        history.rateDamage = rateDamageAfter(b, equivalentStretchNowM, dtS);
        return true;
    }
    return increaseM > 0.0 || crushing;
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
