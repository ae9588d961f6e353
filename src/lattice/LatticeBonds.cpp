// The bonds' pass of a lattice step: each bond's strain in its half-way frame, its damage and its
// spring, dashpot and bending terms (measureBond, each bond writing only its own entry); each
// particle's volumetric strain; and each particle gathering its six bonds' forces in face order,
// each completed with the volumetric force, so the sums do not depend on the thread count.
#include "BondStrainBatch.h"
#include "LatticeBondLaws.h"
#include "LatticeForEach.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>

namespace spall {

void Lattice::computeVolumetricStrain()
{
    mVolumetricStrain.resize(particleCount());
    mVolumetricStressShare.resize(particleCount());
    const bool crushes = !mUncrushedLambdaTracePa.empty();
    const double inverseH = 1.0 / mModel.spacingM;
    forEach(
        particleCount(),
        [&](size_t p) {
            double trace = 0.0, uncrushedTrace = 0.0;
            for (int axis = 0; axis < 3; ++axis) {
                double sum = 0.0, uncrushedSum = 0.0;
                for (const int face : {2 * axis, 2 * axis + 1}) {
                    const int32_t b = mModel.bondAcross[p][face];
                    if (b < 0) continue;
                    sum += mBondStretch[size_t(b)].effectiveM * inverseH;
                    if (crushes) uncrushedSum += mBondStretch[size_t(b)].uncrushedM * inverseH;
                }
                trace += sum * mModel.inverseBondCount[p][axis];
                uncrushedTrace += uncrushedSum * mModel.inverseBondCount[p][axis];
            }
            mVolumetricStrain[p] = trace;
            // d(½ λ h³ (tr ε)²) / d(stretch of one bond along the axis) / h³.
            mVolumetricStressShare[p] = mModel.lambdaPa[p] * trace * mModel.inverseBondCount[p];
            if (crushes) mUncrushedLambdaTracePa[p] = mModel.lambdaPa[p] * uncrushedTrace;
        });
}

namespace {

constexpr int kRunCapacity = int(BondStrainRun::kCapacity);

/// Lane `lane` of a run's strains, read in place: its elements lie kCapacity doubles apart, so
/// nothing reads in pairs what the run wrote one by one (a pair's load would wait for both stores).
struct StrainInRun {
    Eigen::Map<const Eigen::Matrix3d, 0, Eigen::Stride<kRunCapacity, 3 * kRunCapacity>> frame;
    Eigen::Map<const Eigen::Vector3d, 0, Eigen::InnerStride<kRunCapacity>> displacementM, rotationRad;
    StrainInRun(const BondStrainRun& run, size_t lane)
        : frame(&run.frame[0][0][lane]), displacementM(&run.displacementM[0][lane]), rotationRad(&run.rotationRad[0][lane])
    {
    }
};

/// The frame times a vector, summed as Eigen's SSE2 code sums a 3 × 3 by a 3-vector (the first
/// two rows as a pair, left to right; the third alone, right first), so results stay bit for bit.
[[gnu::always_inline]] inline Eigen::Vector3d frameTimes(const StrainInRun& s, const Eigen::Vector3d& v)
{
    Eigen::Vector3d out;
    for (int i = 0; i < 2; ++i) out[i] = (s.frame(i, 0) * v[0] + s.frame(i, 1) * v[1]) + s.frame(i, 2) * v[2];
    out[2] = s.frame(2, 0) * v[0] + (s.frame(2, 1) * v[1] + s.frame(2, 2) * v[2]);
    return out;
}

/// Writes one bond's strain into lane `lane` of a run.
void storeStrain(const BondStrain& s, size_t lane, BondStrainRun& run)
{
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) run.frame[r][c][lane] = s.frame(r, c);
        run.displacementM[r][lane] = s.displacementM[r];
        run.rotationRad[r][lane] = s.rotationRad[r];
    }
}

/// Lane `lane`'s rotation again by the arctangent, in the frame the run measured.
void storeLargeTurn(const Eigen::Quaterniond& qa, const Eigen::Quaterniond& qb, size_t lane, BondStrainRun& run)
{
    const Eigen::Matrix3d frame = StrainInRun(run, lane).frame;
    const Eigen::Vector3d turnRad = bond_laws::largeTurnRad(frame, qa, qb);
    for (int r = 0; r < 3; ++r) run.rotationRad[r][lane] = turnRad[r];
}

// measureBonds reads the particles' and bonds' arrays as flat words.
static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double) && sizeof(Eigen::Quaterniond) == 4 * sizeof(double));
static_assert(sizeof(LatticeBond) == 4 * sizeof(uint32_t) && offsetof(LatticeBond, low) == 0 && offsetof(LatticeBond, high) == 4 &&
              offsetof(LatticeBond, axis) == 8 && sizeof(LatticeBond::axis) == 4);

}  // namespace

uint8_t Lattice::measureBonds(double dtS, bool growDamage)
{
    if (bondCount() == 0) return 0;
    const BondStrainInputs inputs{state.positionM.front().data(), state.velocityMS.front().data(), state.orientation.front().coeffs().data(),
                                  reinterpret_cast<const uint32_t*>(mModel.bonds.data()), mModel.spacingM};
    constexpr size_t capacity = BondStrainRun::kCapacity;
    std::atomic<uint8_t> events{0};
    forEach((bondCount() + capacity - 1) / capacity, [&](size_t r) {
        BondStrainRun run;
        const size_t first = r * capacity, count = std::min(capacity, bondCount() - first);
        measureBondStrains(inputs, first, count, run);
        // A pin is measured alone; a turn too large for the run's series takes the arctangent.
        for (size_t lane = 0; lane < count; ++lane) {
            const LatticeBond& bond = mModel.bonds[first + lane];
            if (bond.pinned)
                storeStrain(strainOf(bond), lane, run);
            else if (run.smallTurn[lane] == 0.0)
                storeLargeTurn(state.orientation[bond.low], state.orientation[bond.high], lane, run);
        }
        uint8_t runEvents = 0;
        for (size_t lane = 0; lane < count; ++lane) runEvents |= measureBond(first + lane, run, lane, dtS, growDamage);
        if (runEvents) events.fetch_or(runEvents, std::memory_order_relaxed);
    }, std::max<size_t>(1, kCheapGrain / capacity));  // as many bonds a task as one bond at a time had
    return events.load();
}

uint8_t Lattice::measureBond(size_t b, const BondStrainRun& run, size_t lane, double dtS, bool growDamage)
{
    const LatticeBond& bond = mModel.bonds[b];
    const LatticeStiffness& k = mModel.stiffness;
    const StrainInRun s(run, lane);
    const int a = bond.axis;
    BondForceTerms& terms = mBondTerms[b];
    const Eigen::Vector3d armM(run.armM[0][lane], run.armM[1][lane], run.armM[2][lane]);
    const double lengthM = run.lengthM[lane];
    const Eigen::Vector3d along = armM * (1.0 / lengthM);
    const double openingRateMS = run.openingRateMS[lane];
    const BondHistory& history = state.bondHistory[b];
    const LatticeStiffness::Strength& strength = k.strength[bond.strengthClass];
    const double damageBefore = bond_laws::bondDamage(history, strength, mModel.damageLaw);
    double damage = damageBefore;
    if (growDamage && growBondDamage(b, equivalentStretchM(b, s, lengthM, damage), crushingShorteningM(b, s.displacementM[a]),
                                     std::abs(openingRateMS) / mModel.spacingM, dtS))
        damage = bond_laws::bondDamage(history, strength, mModel.damageLaw);
    // Compression carries what crushing left (a crack in tension or shear closes on itself).
    const double crushed = bond_laws::crushingDamage(history, strength), uncrushed = 1.0 - crushed;
    const bool broke = damage >= 1.0 && damageBefore < 1.0;
    // What a pin held is lost where it fails (the glazing's own dissipation).
    const bool snapped = broke && mModel.damageLaw == LatticeDamageLaw::Softening && bond_laws::snapsAtPeak(strength) && !bond.pinned &&
                         bond_laws::crackingDamage(history, strength, mModel.damageLaw) >= 1.0;
    if (snapped) mSnapped[b] = 1;
    const double intact = 1.0 - damage, sqrtIntact = std::sqrt(intact);
    const bool opening = lengthM > mModel.spacingM;
    // Element by element (a store into element a after a store of the whole made its next read
    // wait for both).
    Eigen::Vector3d local;
    for (int i = 0; i < 3; ++i) local[i] = (i == a ? -intact * k.normalNPerM[a] : -intact * k.shearNPerM[a][i]) * s.displacementM[i];
    terms.forceOnHighN = frameTimes(s, local);
    if (bond.pinned) {
        // Across its axis only: no contact, dashpot, moment or volumetric share.
        terms.bendingMomentNm.setZero();
        terms.volumetricAreaPerArmM = 0.0;
        mBondStretch[b] = BondStretch();
        return uint8_t(broke ? kBroke : 0);
    }
    // What cracking took still carries compression, as contact: along the line of centres, and
    // only while the two cubes overlap. (In the bond's frame it would push apart particles that
    // have slid past each other or turned over, which feeds energy into a shattered lattice.)
    const double overlapM = mModel.spacingM - lengthM;
    if (intact < uncrushed && overlapM > 0.0) terms.forceOnHighN += (uncrushed - intact) * k.normalNPerM[a] * overlapM * along;
    // The crushed part's rubble carries again once squeezed past the softening line's end:
    // k (D_c overlap − uf), which grows with D_c from nothing, so no force jumps in.
    const double rubbleM = crushed * overlapM - strength.crushingEndShorteningM;
    if (crushed > 0.0 && rubbleM > 0.0) terms.forceOnHighN += k.normalNPerM[a] * rubbleM * along;
    // A crack opening carries no viscous stress either: the dashpot softens with the spring.
    if (mModel.bulkViscosity > 0.0) terms.forceOnHighN -= (opening ? intact : uncrushed) * mModel.bulkViscosity * mModel.dashpotPerViscosityNSPerM * openingRateMS * along;
    Eigen::Vector3d bending;
    for (int i = 0; i < 3; ++i) bending[i] = (i == a ? -intact * k.twistingNmPerRad[a] : -intact * k.bendingNmPerRad[a]) * s.rotationRad[i];
    terms.bendingMomentNm = frameTimes(s, bending);
    const double sqrtUncrushed = crushed == 0.0 ? 1.0 : std::sqrt(uncrushed);
    BondStretch& stretch = mBondStretch[b];
    stretch.uncrushedM = opening ? sqrtIntact * (lengthM - mModel.spacingM) : lengthM - mModel.spacingM;
    stretch.effectiveM = opening ? stretch.uncrushedM : sqrtUncrushed * stretch.uncrushedM;
    terms.volumetricAreaPerArmM = (opening ? sqrtIntact : sqrtUncrushed) * mModel.spacingM * mModel.spacingM / lengthM;
    return uint8_t((snapped ? kSnapped : 0) | (broke ? kBroke : 0));
}

void Lattice::gatherBondForces(size_t p)
{
    Eigen::Vector3d force = Eigen::Vector3d::Zero(), moment = Eigen::Vector3d::Zero();
    for (int face = 0; face < 6; ++face) {
        const int32_t b = mModel.bondAcross[p][face];
        if (b < 0) continue;
        const LatticeBond& bond = mModel.bonds[size_t(b)];
        const Eigen::Vector3d armM = armOf(size_t(b));
        const Eigen::Vector3d forceOnHighN = completeBondForce(size_t(b), armM);
        const Eigen::Vector3d pairMomentNm = bond.pinned ? Eigen::Vector3d::Zero() : Eigen::Vector3d(-0.5 * armM.cross(forceOnHighN));
        const Eigen::Vector3d& bendingMomentNm = mBondTerms[size_t(b)].bendingMomentNm;
        if (face & 1) {  // the bond across p's +axis face: p is its low end
            force -= forceOnHighN;
            moment += pairMomentNm - bendingMomentNm;
            // Read across its particles by the next substep's crushing (confinementPa).
            if (!mBondNormalStressPa.empty())
                mBondNormalStressPa[size_t(b)] = -forceOnHighN.dot(armM) / (armM.norm() * mModel.spacingM * mModel.spacingM);
        } else {
            force += forceOnHighN;
            moment += pairMomentNm + bendingMomentNm;
        }
    }
    state.bondForceN[p] = force;
    state.bondMomentNm[p] = moment;
}

}  // namespace spall
