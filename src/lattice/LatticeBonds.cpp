// The bonds' pass of a lattice step: each bond's strain in its half-way frame, its damage and its
// force terms (in batches for the bonds whose damage stays as it is, BondStrainBatch.h; else
// measureBond, each bond writing only its own entry); each
// particle's volumetric strain; and each particle gathering its six bonds' forces in face order,
// each completed with the volumetric force, so the sums do not depend on the thread count.
#include "BondStrainBatch.h"
#include "LatticeBondLaws.h"
#include "LatticeForEach.h"

#include <algorithm>
#include <array>
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

/// A lane of a run's 3-vector, read in place as v[i]: its elements lie kCapacity doubles apart, so
/// nothing reads in pairs what the run wrote one by one (a pair's load would wait for both stores).
struct LaneVector {
    const double (*components)[kRunCapacity];
    size_t lane;
    double operator[](int i) const { return components[i][lane]; }
};
/// A lane of a run's frame, read in place as frame[row][column].
struct LaneFrame {
    const double (*rows)[3][kRunCapacity];
    size_t lane;
    LaneVector operator[](int r) const { return {rows[r], lane}; }
};
/// A lane of a run's displacement and rotation, as Lattice::equivalentStretchM reads a strain.
struct LaneStrain {
    LaneVector displacementM, rotationRad;
};

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
    Eigen::Matrix3d frame;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) frame(r, c) = run.frame[r][c][lane];
    const Eigen::Vector3d turnRad = bond_laws::largeTurnRad(frame, qa, qb);
    for (int r = 0; r < 3; ++r) run.rotationRad[r][lane] = turnRad[r];
}

/// force += magnitude × along, element by element.
void addAlong(double magnitudeN, const double (&along)[3], double (&forceN)[3])
{
    for (int i = 0; i < 3; ++i) forceN[i] += magnitudeN * along[i];
}

/// The compression what cracking and crushing took still carries, along the line of centres (a
/// unit vector `along`), added to the force on high: cracking's part as contact while the two
/// cubes overlap (in the bond's frame it would push apart particles that have slid past each
/// other or turned over, which feeds energy into a shattered lattice); the crushed part's rubble
/// once squeezed past the softening line's end (`crushingEndM`), k (D_c overlap − uf), which
/// grows with D_c from nothing, so no force jumps in.
void addClosedCrackForces(double intact, double crushed, double overlapM, double normalNPerM, double crushingEndM, const double (&along)[3],
                          double (&forceOnHighN)[3])
{
    const double uncrushed = 1.0 - crushed;
    if (intact < uncrushed && overlapM > 0.0) addAlong((uncrushed - intact) * normalNPerM * overlapM, along, forceOnHighN);
    const double rubbleM = crushed * overlapM - crushingEndM;
    if (crushed > 0.0 && rubbleM > 0.0) addAlong(normalNPerM * rubbleM, along, forceOnHighN);
}

/// Per component of the frame of a bond along axis `a`: its normal spring along the axis and its
/// shear springs across it; its twisting stiffness about the axis and its bending about the
/// others (bond_law::elasticTerms).
void axisStiffnesses(const LatticeStiffness& k, int a, double (&springNPerM)[3], double (&turnNmPerRad)[3])
{
    for (int i = 0; i < 3; ++i) {
        springNPerM[i] = i == a ? k.normalNPerM[size_t(a)] : k.shearNPerM[size_t(a)][i];
        turnNmPerRad[i] = i == a ? k.twistingNmPerRad[size_t(a)] : k.bendingNmPerRad[size_t(a)];
    }
}

/// The rows the batches read for each strength class and axis (BondLawRow).
std::array<BondLawRow, 6> bondLawRows(const LatticeModel& model)
{
    const LatticeStiffness& k = model.stiffness;
    std::array<BondLawRow, 6> rows{};
    for (size_t strengthClass = 0; strengthClass < 2; ++strengthClass)
        for (size_t a = 0; a < 3; ++a) {
            const LatticeModel::FailureTerms& terms = model.failureTerms[strengthClass][a];
            const LatticeStiffness::Strength& strength = k.strength[strengthClass];
            BondLawRow& row = rows[3 * strengthClass + a];
            axisStiffnesses(k, int(a), row.springNPerM, row.turnNmPerRad);
            const double shearB = terms.shearIndexPerM[int((a + 1) % 3)], shearC = terms.shearIndexPerM[int((a + 2) % 3)];
            row.peakStretchM = terms.peakStretchM, row.tensionIndexPerM = terms.tensionIndexPerM, row.shearIndexPerM = shearB;
            row.normalIndexPerM = terms.normalIndexPerM, row.indexPerPa = terms.indexPerPa, row.frictionCoefficient = terms.frictionCoefficient;
            row.compressiveStrengthPa = strength.compressiveStrengthPa, row.crushingPeakShorteningM = strength.crushingPeakShorteningM;
            row.normalModulusPa = k.normalModulusPa[a], row.zeroTractionStretchM = strength.zeroTractionStretchM;
            // One peak for the index and the softening line, and one shear index across the axis.
            row.batches = shearB == shearC && terms.peakStretchM == strength.peakStretchM ? 1.0 : 0.0;
        }
    return rows;
}

// measureBonds reads the particles' and bonds' arrays as flat words.
static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double) && sizeof(Eigen::Quaterniond) == 4 * sizeof(double));
static_assert(sizeof(LatticeBond) == 4 * sizeof(uint32_t) && offsetof(LatticeBond, low) == 0 && offsetof(LatticeBond, high) == 4 &&
              offsetof(LatticeBond, axis) == 8 && sizeof(LatticeBond::axis) == 4 && offsetof(LatticeBond, strengthClass) == 12 &&
              offsetof(LatticeBond, pinned) == 13);
static_assert(sizeof(BondHistory) == kHistoryWords * sizeof(double) && offsetof(BondHistory, strengthScale) == kStrengthScaleWord * sizeof(double) &&
              offsetof(BondHistory, maxEquivalentStretchM) == kMaxEquivalentStretchWord * sizeof(double) &&
              offsetof(BondHistory, strengthFactor) == kStrengthFactorWord * sizeof(double) &&
              offsetof(BondHistory, maxCrushingShorteningM) == kMaxCrushingWord * sizeof(double));

}  // namespace

uint8_t Lattice::measureBonds(double dtS, bool growDamage)
{
    if (bondCount() == 0) return 0;
    BondStrainInputs inputs{state.positionM.front().data(), state.velocityMS.front().data(), state.orientation.front().coeffs().data(),
                            reinterpret_cast<const uint32_t*>(mModel.bonds.data()), mModel.spacingM};
    // The batches find the bonds whose damage stays where that is all a step can do to them:
    // damage grows on the softening line (Davison–Stevens grows it every step).
    // (The volumetric shares are sized by the first force pass, after its bonds are measured.)
    std::array<BondLawRow, 6> rows;
    BondLawInputs laws;
    if (mBatchesSteadyBonds && growDamage && mModel.damageLaw == LatticeDamageLaw::Softening && mVolumetricStressShare.size() == particleCount()) {
        rows = bondLawRows(mModel);
        laws = {rows.data(), &state.bondHistory.front().strengthScale, mVolumetricStressShare.front().data(),
                mUncrushedLambdaTracePa.empty() ? nullptr : mUncrushedLambdaTracePa.data(), mModel.bulkViscosity, mModel.dashpotPerViscosityNSPerM};
        inputs.laws = &laws;
    }
    constexpr size_t capacity = BondStrainRun::kCapacity;
    std::atomic<uint8_t> events{0};
    std::atomic<size_t> batched{0};
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
        size_t runBatched = 0;
        for (size_t lane = 0; lane < count; ++lane) {
            if (inputs.laws && run.steady[lane] != 0.0) {
                takeSteadyTerms(first + lane, run, lane);
                ++runBatched;
            } else {
                runEvents |= measureBond(first + lane, run, lane, dtS, growDamage);
            }
        }
        if (runEvents) events.fetch_or(runEvents, std::memory_order_relaxed);
        batched.fetch_add(runBatched, std::memory_order_relaxed);
    }, std::max<size_t>(1, kCheapGrain / capacity));  // as many bonds a task as one bond at a time had
    mBondsBatchedInLastPass = batched.load();
    return events.load();
}

void Lattice::takeSteadyTerms(size_t b, const BondStrainRun& run, size_t lane)
{
    BondForceTerms& terms = mBondTerms[b];
    for (int k = 0; k < 3; ++k) terms.forceOnHighN[k] = run.forceOnHighN[k][lane], terms.bendingMomentNm[k] = run.bendingMomentNm[k][lane];
    terms.volumetricAreaPerArmM = run.volumetricAreaPerArmM[lane];
    mBondStretch[b].effectiveM = mBondStretch[b].uncrushedM = run.stretchM[lane];
}

uint8_t Lattice::measureBond(size_t b, const BondStrainRun& run, size_t lane, double dtS, bool growDamage)
{
    const LatticeBond& bond = mModel.bonds[b];
    const LatticeStiffness& k = mModel.stiffness;
    const LaneStrain s{{run.displacementM, lane}, {run.rotationRad, lane}};
    const int a = bond.axis;
    BondForceTerms& terms = mBondTerms[b];
    const double lengthM = run.lengthM[lane];
    const double inverseLength = 1.0 / lengthM;
    const double along[3] = {run.armM[0][lane] * inverseLength, run.armM[1][lane] * inverseLength, run.armM[2][lane] * inverseLength};
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
    if (broke) mBroken[b] = 1;
    // What a pin held is lost where it fails (the glazing's own dissipation).
    const bool snapped = broke && mModel.damageLaw == LatticeDamageLaw::Softening && bond_laws::snapsAtPeak(strength) && !bond.pinned &&
                         bond_laws::crackingDamage(history, strength, mModel.damageLaw) >= 1.0;
    if (snapped) mSnapped[b] = 1;
    const double intact = 1.0 - damage, sqrtIntact = std::sqrt(intact);
    const bool opening = lengthM > mModel.spacingM;
    double forceOnHighN[3], momentNm[3], springNPerM[3], turnNmPerRad[3];
    axisStiffnesses(k, a, springNPerM, turnNmPerRad);
    bond_law::elasticTerms(LaneFrame{run.frame, lane}, s.displacementM, s.rotationRad, springNPerM, turnNmPerRad, intact, forceOnHighN, momentNm);
    if (bond.pinned) {
        // Across its axis only: no contact, dashpot, moment or volumetric share.
        terms.forceOnHighN = Eigen::Vector3d(forceOnHighN[0], forceOnHighN[1], forceOnHighN[2]);
        terms.bendingMomentNm.setZero();
        terms.volumetricAreaPerArmM = 0.0;
        mBondStretch[b] = BondStretch();
        return uint8_t(broke ? kBroke : 0);
    }
    addClosedCrackForces(intact, crushed, mModel.spacingM - lengthM, k.normalNPerM[a], strength.crushingEndShorteningM, along, forceOnHighN);
    // A crack opening carries no viscous stress either: the dashpot softens with the spring.
    if (mModel.bulkViscosity > 0.0)
        bond_law::subtractDashpot(opening ? intact : uncrushed, mModel.bulkViscosity, mModel.dashpotPerViscosityNSPerM, openingRateMS, along, forceOnHighN);
    terms.forceOnHighN = Eigen::Vector3d(forceOnHighN[0], forceOnHighN[1], forceOnHighN[2]);
    terms.bendingMomentNm = Eigen::Vector3d(momentNm[0], momentNm[1], momentNm[2]);
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
