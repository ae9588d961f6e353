#include <spall/dynamics/Dynamics.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace spall {

Integrator parseIntegrator(const std::string& name)
{
    if (name == "explicit-euler") return Integrator::ExplicitEuler;
    if (name == "semi-implicit-euler") return Integrator::SemiImplicitEuler;
    if (name == "rk4") return Integrator::RungeKutta4;
    throw InputError("integrator '" + name + "' is unknown (expected explicit-euler, semi-implicit-euler or rk4)");
}

std::string toString(Integrator integrator)
{
    switch (integrator) {
    case Integrator::ExplicitEuler: return "explicit-euler";
    case Integrator::SemiImplicitEuler: return "semi-implicit-euler";
    case Integrator::RungeKutta4: return "rk4";
    }
    return "semi-implicit-euler";
}

Wrench blastWrench(const Body& body, const Eigen::Vector3d& positionM, const Eigen::Quaterniond& orientation,
                   const BlastField& field, const std::vector<OpenWindow>& windows, double timeS, bool reflectedPressure)
{
    Wrench total;
    if (windows.empty() || body.exposedFaces.empty()) return total;
    const double h = body.voxelSizeM;
    const double faceArea = h * h;
    const Eigen::Matrix3d rot = orientation.toRotationMatrix();
    const double p0 = field.settings().atmosphere.pressurePa;
    constexpr size_t kBlock = 4096;
    const size_t blocks = (body.exposedFaces.size() + kBlock - 1) / kBlock;
    std::vector<Wrench> partial(blocks);
    auto sumBlock = [&](size_t b) {
        Wrench w;
        const size_t end = std::min(body.exposedFaces.size(), (b + 1) * kBlock);
        for (size_t i = b * kBlock; i < end; ++i) {
            const ExposedFace& f = body.exposedFaces[i];
            const Eigen::Vector3d normal = rot.col(faceAxis(f.face)) * faceSign(f.face);
            const Eigen::Vector3d arm = rot * body.voxelOffsetM(f.voxel) + 0.5 * h * normal;
            const Eigen::Vector3d x = positionM + arm;
            field.forEachCharge(x, timeS, windows, [&](int, double p, const Eigen::Vector3d& charge) {
                const Eigen::Vector3d r = x - charge;
                const double distance = r.norm();
                if (distance <= 0) return;
                const Eigen::Vector3d rHat = r / distance;
                const double cosine = -normal.dot(rHat);
                if (cosine <= 0.0) return;  // the face looks away from this charge
                double pressure = p;
                if (reflectedPressure && p > 0) {
                    const double reflected = 2.0 * p * (7.0 * p0 + 4.0 * p) / (7.0 * p0 + p);
                    pressure = p + (reflected - p) * cosine * cosine;
                }
                const Eigen::Vector3d force = pressure * faceArea * cosine * rHat;
                w.forceN += force;
                w.torqueNm += arm.cross(force);
            });
        }
        partial[b] = w;
    };
    if (blocks == 1) {
        sumBlock(0);
    } else {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t b = r.begin(); b != r.end(); ++b) sumBlock(b);
        });
    }
    for (const Wrench& w : partial) {
        total.forceN += w.forceN;
        total.torqueNm += w.torqueNm;
    }
    return total;
}

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

/// Exact rotation by w over dt: exp(w dt / 2) q.
Eigen::Quaterniond rotateBy(const Eigen::Quaterniond& q, const Eigen::Vector3d& w, double dt)
{
    const double angle = w.norm() * dt;
    if (angle < 1e-300) return q;
    return (Eigen::Quaterniond(Eigen::AngleAxisd(angle, w.normalized())) * q).normalized();
}

}  // namespace

void integrateBody(Body& body, double t, double dt, Integrator integrator, const WrenchFunction& wrench)
{
    const double m = body.mass.massKg;
    RigidState s{body.positionM, body.orientation, m * body.linearVelocityMS,
                 body.worldInertiaKgM2() * body.angularVelocityRadS};
    switch (integrator) {
    case Integrator::ExplicitEuler: {
        // The paper's method: every derivative from the state at the start of the step.
        const Wrench w = wrench(t, s.x, s.q, body.linearVelocityMS, body.angularVelocityRadS);
        const Eigen::Quaterniond dq = quaternionRate(s.q, body.angularVelocityRadS);
        s.x += dt * body.linearVelocityMS;
        s.q.coeffs() += dt * dq.coeffs();
        s.q.normalize();
        s.p += dt * w.forceN;
        s.l += dt * w.torqueNm;
        break;
    }
    case Integrator::SemiImplicitEuler: {
        // Symplectic: momenta first, then pose with the new velocities; rotation is exact for
        // the step's angular velocity.
        const Wrench w = wrench(t, s.x, s.q, body.linearVelocityMS, body.angularVelocityRadS);
        s.p += dt * w.forceN;
        s.l += dt * w.torqueNm;
        s.x += dt * s.p / m;
        s.q = rotateBy(s.q, angularVelocity(body, s.q, s.l), dt);
        break;
    }
    case Integrator::RungeKutta4: {
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
        break;
    }
    }
    body.positionM = s.x;
    body.orientation = s.q;
    body.linearVelocityMS = s.p / m;
    body.angularVelocityRadS = angularVelocity(body, s.q, s.l);
}

double kineticEnergyJ(const Body& body)
{
    return 0.5 * body.mass.massKg * body.linearVelocityMS.squaredNorm() +
           0.5 * body.angularVelocityRadS.dot(body.worldInertiaKgM2() * body.angularVelocityRadS);
}

Eigen::Vector3d linearMomentum(const Body& body) { return body.mass.massKg * body.linearVelocityMS; }

Eigen::Vector3d angularMomentumAboutOrigin(const Body& body)
{
    return body.worldInertiaKgM2() * body.angularVelocityRadS + body.positionM.cross(linearMomentum(body));
}

}  // namespace spall
