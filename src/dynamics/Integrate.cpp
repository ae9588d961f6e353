#include <spall/dynamics/Integrate.h>

#include <spall/core/Parallel.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace spall {

namespace {

struct RigidState {
    Eigen::Vector3d x;
    Eigen::Quaterniond q;
    Eigen::Vector3d p;  ///< linear momentum
    Eigen::Vector3d l;  ///< angular momentum
};

Eigen::Vector3d angularVelocity(const Body& body, const Eigen::Quaterniond& q, const Eigen::Vector3d& l)
{
    // w = R I^-1 R^T L, with the body-frame inertia solved (symmetric positive definite).
    const Eigen::Matrix3d r = q.toRotationMatrix();
    return r * body.mass.inertiaKgM2.ldlt().solve(r.transpose() * l);
}

/// Quaternion rate: dq/dt = 1/2 (0, w) q.
Eigen::Quaterniond quaternionRate(const Eigen::Quaterniond& q, const Eigen::Vector3d& w)
{
    Eigen::Quaterniond dq = Eigen::Quaterniond(0, w.x(), w.y(), w.z()) * q;
    dq.coeffs() *= 0.5;
    return dq;
}

/// The torque-free rotation over dt with the world angular momentum l fixed, by the symmetric
/// splitting of Dullweber, Leimkuhler & McLachlan (J. Chem. Phys. 107 (1997) 5840): turns about
/// the principal axes 1, 2, 3, 2, 1 for dt/2, dt/2, dt, dt/2, dt/2, each exact. It keeps |l| and
/// stays on the energy surface to O(dt²) without drift, where turning by the step's starting ω
/// lets a long thin spinning piece gain energy without bound (the rotation error feeds the
/// spin about its axis of least inertia, the direction of highest energy for its momentum).
/// Its error grows as the square of the turn: a chip spinning at thousands of rad/s turns
/// several radians in a long step, and there it gained 45 % of its energy in half a second. So
/// the flow is taken in pieces of at most kMaxTurnRad each (a few for such a chip, one for nearly
/// every body).
constexpr double kMaxTurnRad = 0.1;

Eigen::Quaterniond rotateTorqueFree(const Body& body, const Eigen::Quaterniond& q, const Eigen::Vector3d& l, double dt)
{
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> principal;
    principal.computeDirect(body.mass.inertiaKgM2);
    const Eigen::Vector3d moments = principal.eigenvalues();
    // The principal frame in the world: R_p = R V.
    Eigen::Matrix3d frame = q.toRotationMatrix() * principal.eigenvectors();
    auto turnAbout = [&](int axis, double time) {
        const double angle = frame.col(axis).dot(l) / moments[axis] * time;
        frame = frame * Eigen::AngleAxisd(angle, Eigen::Vector3d::Unit(axis)).toRotationMatrix();
    };
    // |ω| ≤ |l| / I_min however l moves among the axes (eigenvalues come in increasing order);
    // a non-finite turn is left to the caller's check of the motion (refuseNonFiniteMotion).
    const double turns = l.norm() / moments[0] * dt / kMaxTurnRad;
    const int pieces = std::isfinite(turns) ? static_cast<int>(std::clamp(std::ceil(turns), 1.0, 1e6)) : 1;
    const double piece = dt / pieces;
    for (int k = 0; k < pieces; ++k) {
        turnAbout(0, 0.5 * piece);
        turnAbout(1, 0.5 * piece);
        turnAbout(2, piece);
        turnAbout(1, 0.5 * piece);
        turnAbout(0, 0.5 * piece);
    }
    return Eigen::Quaterniond(frame * principal.eigenvectors().transpose()).normalized();
}

/// Classic fourth-order Runge–Kutta over the whole state; the quaternion is normalised at the end.
RigidState rungeKutta4Step(const Body& body, const RigidState& s0, double t, double dt, const WrenchFunction& wrench)
{
    const double m = body.mass.massKg;
    RigidState s = s0;
    struct Derivative {
        Eigen::Vector3d dx;
        Eigen::Quaterniond dq;
        Eigen::Vector3d dp, dl;
    };
    auto derivative = [&](double time, const RigidState& st) {
        const Eigen::Vector3d v = st.p / m;
        const Eigen::Vector3d w = angularVelocity(body, st.q.normalized(), st.l);
        const Wrench f = wrench(time, st.x, st.q.normalized(), v, w);
        return Derivative{v, quaternionRate(st.q, w), f.forceN, f.torqueNm};
    };
    auto advance = [](const RigidState& st, const Derivative& d, double h) {
        RigidState out = st;
        out.x += h * d.dx;
        out.q.coeffs() += h * d.dq.coeffs();
        out.p += h * d.dp;
        out.l += h * d.dl;
        return out;
    };
    const Derivative k1 = derivative(t, s);
    const Derivative k2 = derivative(t + dt / 2, advance(s, k1, dt / 2));
    const Derivative k3 = derivative(t + dt / 2, advance(s, k2, dt / 2));
    const Derivative k4 = derivative(t + dt, advance(s, k3, dt));
    s.x += dt / 6 * (k1.dx + 2 * k2.dx + 2 * k3.dx + k4.dx);
    s.q.coeffs() += dt / 6 * (k1.dq.coeffs() + 2 * k2.dq.coeffs() + 2 * k3.dq.coeffs() + k4.dq.coeffs());
    s.q.normalize();
    s.p += dt / 6 * (k1.dp + 2 * k2.dp + 2 * k3.dp + k4.dp);
    s.l += dt / 6 * (k1.dl + 2 * k2.dl + 2 * k3.dl + k4.dl);
    return s;
}

}  // namespace

void integrateBody(Body& body, double t, double dt, Integrator integrator, const WrenchFunction& wrench)
{
    const double m = body.mass.massKg;
    RigidState s{body.motion.positionM, body.motion.orientation, m * body.motion.linearVelocityMS,
                 body.worldInertiaKgM2() * body.motion.angularVelocityRadS};
    switch (integrator) {
    case Integrator::ExplicitEuler: {
        // The paper's method: every derivative from the state at the start of the step.
        const Wrench w = wrench(t, s.x, s.q, body.motion.linearVelocityMS, body.motion.angularVelocityRadS);
        const Eigen::Quaterniond dq = quaternionRate(s.q, body.motion.angularVelocityRadS);
        s.x += dt * body.motion.linearVelocityMS;
        s.q.coeffs() += dt * dq.coeffs();
        s.q.normalize();
        s.p += dt * w.forceN;
        s.l += dt * w.torqueNm;
        break;
    }
    case Integrator::SemiImplicitEuler: {
        // Symplectic: momenta first, then pose with the new momenta, the rotation by the
        // torque-free flow of the new angular momentum.
        const Wrench w = wrench(t, s.x, s.q, body.motion.linearVelocityMS, body.motion.angularVelocityRadS);
        s.p += dt * w.forceN;
        s.l += dt * w.torqueNm;
        s.x += dt * s.p / m;
        s.q = rotateTorqueFree(body, s.q, s.l, dt);
        break;
    }
    case Integrator::RungeKutta4: s = rungeKutta4Step(body, s, t, dt, wrench); break;
    }
    body.motion.positionM = s.x;
    body.motion.orientation = s.q;
    body.motion.linearVelocityMS = s.p / m;
    body.motion.angularVelocityRadS = angularVelocity(body, s.q, s.l);
}

void integrateBodies(std::vector<Body>& bodies, const std::vector<Wrench>& blast, const WorldSettings& world, const Air& air,
                     Integrator integrator, double timeS, double dt)
{
    const bool airDrag = world.airDrag == AirDrag::HaiderLevenspiel;
    forEachIndex(bodies.size(), [&](size_t i) {
        Body& body = bodies[i];
        if (!movable(body)) return;
        const double m = body.mass.massKg;
        const DragShape shape = airDrag ? dragShapeOf(body) : DragShape();
        auto wrench = [&](double, const Eigen::Vector3d&, const Eigen::Quaterniond& q, const Eigen::Vector3d& v, const Eigen::Vector3d& w) {
            Wrench total = blast[i];
            total.forceN += m * world.gravityMS2 - world.linearDragPerS * m * v;
            if (airDrag) total.forceN += airDragForceN(shape, air, v);
            const Eigen::Matrix3d r = q.toRotationMatrix();
            total.torqueNm -= world.angularDragPerS * (r * body.mass.inertiaKgM2 * r.transpose() * w);
            return total;
        };
        integrateBody(body, timeS, dt, integrator, wrench);
    });
}

double kineticEnergyJ(const Body& body)
{
    return 0.5 * body.mass.massKg * body.motion.linearVelocityMS.squaredNorm() +
           0.5 * body.motion.angularVelocityRadS.dot(body.worldInertiaKgM2() * body.motion.angularVelocityRadS);
}

Eigen::Vector3d linearMomentum(const Body& body) { return body.mass.massKg * body.motion.linearVelocityMS; }

Eigen::Vector3d angularMomentumAboutOrigin(const Body& body)
{
    return body.worldInertiaKgM2() * body.motion.angularVelocityRadS + body.motion.positionM.cross(linearMomentum(body));
}

}  // namespace spall
