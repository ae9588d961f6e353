// A bond's strain in its half-way frame, written once for one bond (T = double: strainOf) and for
// a batch of bonds side by side (T = an xsimd batch of doubles: BondStrainBatch.cpp), so the bond
// pass can measure many bonds per instruction (issue 49). Each expression adds and multiplies in
// the order Eigen's SSE2 code does (a quaternion's dot as (x x' + z z') + (y y' + w w'), its
// product as Eigen's quat_product, a 3-vector's sums left to right), so the batch and the single
// bond agree bit for bit, with each other and with the lattice before the batches.
//
// No Eigen here, and everything in an unnamed namespace: the batch translation units are compiled
// for wider instruction sets than the rest, and must not lend the rest their copies.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace spall {
namespace {
namespace bond_strain {

/// a where the condition holds, else b: for one bond, or lane by lane (xsimd's select, by
/// argument-dependent lookup).
template <typename Mask, typename T>
T selectLanes(const Mask& condition, const T& a, const T& b)
{
    if constexpr (std::is_same_v<Mask, bool>)
        return condition ? a : b;
    else
        return select(condition, a, b);
}

/// What a bond's particles hold, for one bond or a batch: positions, velocities and orientation
/// quaternions (x, y, z, w).
template <typename T>
struct EndState {
    T position[3], velocity[3], quaternion[4];
};

/// Its half-way frame (columns: the frame's axes in the world), displacement of high relative to
/// low less the rest length along the bond's axis, and rotation of high relative to low, in the
/// frame; the arm between the particles (world), its length and the rate it opens at.
template <typename T>
struct Strain {
    T frame[3][3];  ///< frame[row][column]
    T displacementM[3], rotationRad[3];
    T armM[3], lengthM, openingRateMS;
};

/// Frame-transposed times a vector: (column i) · v, summed left to right.
template <typename T>
void transposedTimes(const T (&frame)[3][3], const T (&v)[3], T (&out)[3])
{
    for (int i = 0; i < 3; ++i) out[i] = frame[0][i] * v[0] + frame[1][i] * v[1] + frame[2][i] * v[2];
}

/// The rotation matrix of a quaternion of any length (its own normalised): one division, where
/// normalising first takes a root and four.
template <typename T>
void rotationMatrixOf(const T (&q)[4], T (&r)[3][3])
{
    const T x = q[0], y = q[1], z = q[2], w = q[3];
    const T s = T(2.0) / (w * w + x * x + y * y + z * z);
    const T xx = s * x * x, yy = s * y * y, zz = s * z * z, xy = s * x * y, xz = s * x * z, yz = s * y * z;
    const T wx = s * w * x, wy = s * w * y, wz = s * w * z;
    r[0][0] = T(1.0) - yy - zz, r[0][1] = xy - wz, r[0][2] = xz + wy;
    r[1][0] = xy + wz, r[1][1] = T(1.0) - xx - zz, r[1][2] = yz - wx;
    r[2][0] = xz - wy, r[2][1] = yz + wx, r[2][2] = T(1.0) - xx - yy;
}

/// q_b q_a*, the rotation from a's orientation to b's (Eigen's quat_product, operand by operand).
template <typename T>
void relativeRotation(const T (&a)[4], const T (&b)[4], T (&out)[4])
{
    // a's conjugate, its signs flipped by a product: xsimd's AVX-512 negation is 0 − x, which
    // turns −0 into +0 where Eigen's flips the sign bit.
    const T cx = a[0] * T(-1.0), cy = a[1] * T(-1.0), cz = a[2] * T(-1.0), cw = a[3];
    out[0] = (b[3] * cx + b[1] * cz) - (b[2] * cy - b[0] * cw);
    out[1] = (b[3] * cy + b[1] * cw) + (b[2] * cx - b[0] * cz);
    out[2] = (b[3] * cz - b[1] * cx) + (b[2] * cw + b[0] * cy);
    out[3] = (b[3] * cw - b[1] * cy) - (b[2] * cz + b[0] * cx);
}

/// The rotation vector (angle × axis) of a unit quaternion, the short way round, where its angle
/// is small: 2 atan(s/w)/s by its series (relative error below 1e-13 for s/w < 1e-3). `small`
/// says where that holds (s² < 1e-6 w²); elsewhere the caller takes the arctangent.
template <typename T, typename Mask>
void smallRotationVector(const T (&q)[4], T (&out)[3], Mask& small)
{
    const auto negative = q[3] < T(0.0);
    const T sign = selectLanes(negative, T(-1.0), T(1.0));
    const T x = sign * q[0], y = sign * q[1], z = sign * q[2], w = sign * q[3];
    const T s2 = (x * x + y * y) + z * z;
    small = s2 < T(1e-6) * w * w;
    const T inverseW = T(1.0) / w, r2 = s2 * inverseW * inverseW;
    const T factor = T(2.0) * inverseW * (T(1.0) - r2 / T(3.0) + r2 * r2 / T(5.0));
    out[0] = factor * x, out[1] = factor * y, out[2] = factor * z;
}

/// The strain of a bond along `axis` (0, 1, 2 per lane) of rest length `spacingM` between ends
/// `low` and `high`; `smallTurn` is false where the relative rotation is too large for the series
/// (the caller measures those bonds one at a time).
template <typename T, typename Int, typename Mask>
void halfwayStrain(const EndState<T>& low, const EndState<T>& high, const Int& axis, double spacingM, Strain<T>& s, Mask& smallTurn)
{
    const T (&qa)[4] = low.quaternion;
    const T (&qb)[4] = high.quaternion;
    // Half-way between two orientations: their normalised sum (slerp at ½, as qb is near qa).
    const T dot = (qa[0] * qb[0] + qa[2] * qb[2]) + (qa[1] * qb[1] + qa[3] * qb[3]);
    const T hemisphere = selectLanes(dot >= T(0.0), T(1.0), T(-1.0));
    const T half[4] = {qa[0] + hemisphere * qb[0], qa[1] + hemisphere * qb[1], qa[2] + hemisphere * qb[2], qa[3] + hemisphere * qb[3]};
    rotationMatrixOf(half, s.frame);
    for (int i = 0; i < 3; ++i) s.armM[i] = high.position[i] - low.position[i];
    transposedTimes(s.frame, s.armM, s.displacementM);
    for (int i = 0; i < 3; ++i) s.displacementM[i] = selectLanes(axis == Int(i), s.displacementM[i] - T(spacingM), s.displacementM[i]);
    T relative[4], turn[3];
    relativeRotation(qa, qb, relative);
    smallRotationVector(relative, turn, smallTurn);
    transposedTimes(s.frame, turn, s.rotationRad);
    using std::sqrt;
    s.lengthM = sqrt((s.armM[0] * s.armM[0] + s.armM[1] * s.armM[1]) + s.armM[2] * s.armM[2]);
    const T inverseLength = T(1.0) / s.lengthM;
    const T along[3] = {s.armM[0] * inverseLength, s.armM[1] * inverseLength, s.armM[2] * inverseLength};
    T closing[3];
    for (int i = 0; i < 3; ++i) closing[i] = high.velocity[i] - low.velocity[i];
    s.openingRateMS = (closing[0] * along[0] + closing[1] * along[1]) + closing[2] * along[2];
}

}  // namespace bond_strain
}  // namespace
}  // namespace spall
