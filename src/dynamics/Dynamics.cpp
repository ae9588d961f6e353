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

namespace {

struct Contact {
    Eigen::Vector3d arm;     ///< contact point relative to the centre of mass
    Eigen::Vector3d normal;  ///< out of the collider
    double depth;
    int collider;            ///< -1: the ground; else the box index
    double restitution, friction;
    double normalImpulse = 0;
};

/// Corners of the body's boundary voxels inside the ground or a static box.
std::vector<Contact> findStaticContacts(const Body& body, const WorldSettings& world)
{
    std::vector<Contact> contacts;
    const Eigen::Matrix3d rot = body.orientation.toRotationMatrix();
    const double h = body.voxelSizeM;
    const double voxelRadius = 0.5 * std::sqrt(3.0) * h;
    const GroundPlane& ground = world.ground;
    const bool nearGround = ground.enabled && ground.normal.dot(body.positionM) - ground.offsetM <= body.boundingRadiusM;
    std::vector<int> nearBoxes;
    for (size_t b = 0; b < world.colliders.size(); ++b) {
        const StaticBox& box = world.colliders[b];
        const Eigen::Vector3d local = box.orientation.inverse() * (body.positionM - box.centreM);
        const Eigen::Vector3d outside = (local.cwiseAbs() - box.halfExtentM).cwiseMax(0.0);
        if (outside.norm() <= body.boundingRadiusM) nearBoxes.push_back(static_cast<int>(b));
    }
    if (!nearGround && nearBoxes.empty()) return contacts;

    const openvdb::Coord* last = nullptr;
    for (const ExposedFace& f : body.exposedFaces) {
        if (last && *last == f.voxel) continue;
        last = &f.voxel;
        const Eigen::Vector3d centreArm = rot * body.voxelOffsetM(f.voxel);
        const Eigen::Vector3d centre = body.positionM + centreArm;
        // Eight corners per voxel: a face resting on a collider gets four points, so resting
        // bodies do not pivot about a single point.
        auto corners = [&](auto&& visit) {
            for (int c = 0; c < 8; ++c)
                visit(0.5 * h * (rot.col(0) * (c & 1 ? 1 : -1) + rot.col(1) * (c & 2 ? 1 : -1) + rot.col(2) * (c & 4 ? 1 : -1)));
        };
        if (nearGround && ground.normal.dot(centre) - ground.offsetM < voxelRadius) {
            corners([&](const Eigen::Vector3d& corner) {
                const double separation = ground.normal.dot(centre + corner) - ground.offsetM;
                if (separation < 0.0)
                    contacts.push_back({centreArm + corner, ground.normal, -separation, -1, ground.restitution, ground.friction});
            });
        }
        for (int b : nearBoxes) {
            const StaticBox& box = world.colliders[b];
            const Eigen::Matrix3d boxRot = box.orientation.toRotationMatrix();
            const Eigen::Vector3d local = boxRot.transpose() * (centre - box.centreM);
            if (((local.cwiseAbs() - box.halfExtentM).array() > voxelRadius).any()) continue;
            corners([&](const Eigen::Vector3d& corner) {
                const Eigen::Vector3d q = boxRot.transpose() * (centre + corner - box.centreM);
                const Eigen::Vector3d penetration = box.halfExtentM - q.cwiseAbs();
                if ((penetration.array() <= 0.0).any()) return;
                int axis = 0;
                penetration.minCoeff(&axis);
                const Eigen::Vector3d normal = boxRot.col(axis) * (q[axis] >= 0 ? 1.0 : -1.0);
                contacts.push_back({centreArm + corner, normal, penetration[axis], b, box.restitution, box.friction});
            });
        }
    }
    return contacts;
}

}  // namespace

int resolveStaticContacts(Body& body, const WorldSettings& world, double dt)
{
    if (body.anchored) return 0;
    std::vector<Contact> contacts = findStaticContacts(body, world);
    if (contacts.empty()) return 0;

    const Eigen::Matrix3d rot = body.orientation.toRotationMatrix();
    const double invMass = 1.0 / body.mass.massKg;
    const Eigen::Matrix3d invInertia = rot * body.mass.inertiaKgM2.inverse() * rot.transpose();
    Eigen::Vector3d& v = body.linearVelocityMS;
    Eigen::Vector3d& w = body.angularVelocityRadS;
    // Bounce only above the speed gravity adds in a couple of steps, so resting contacts rest.
    const double bounceThreshold = 2.0 * world.gravityMS2.norm() * dt + 0.05;
    std::vector<double> bounceTarget(contacts.size(), 0.0);
    for (size_t i = 0; i < contacts.size(); ++i) {
        const double vn = contacts[i].normal.dot(v + w.cross(contacts[i].arm));
        if (vn < -bounceThreshold) bounceTarget[i] = -contacts[i].restitution * vn;
    }
    auto applyImpulse = [&](const Eigen::Vector3d& arm, const Eigen::Vector3d& impulse) {
        v += invMass * impulse;
        w += invInertia * arm.cross(impulse);
    };
    auto effectiveMass = [&](const Eigen::Vector3d& arm, const Eigen::Vector3d& dir) {
        const Eigen::Vector3d rn = arm.cross(dir);
        return 1.0 / (invMass + rn.dot(invInertia * rn));
    };
    for (int iteration = 0; iteration < 12; ++iteration) {
        for (size_t i = 0; i < contacts.size(); ++i) {
            Contact& c = contacts[i];
            // Normal: the accumulated impulse stays >= 0.
            const double vn = c.normal.dot(v + w.cross(c.arm));
            const double previous = c.normalImpulse;
            c.normalImpulse = std::max(previous + effectiveMass(c.arm, c.normal) * (bounceTarget[i] - vn), 0.0);
            applyImpulse(c.arm, (c.normalImpulse - previous) * c.normal);
            // Friction along the current sliding direction, bounded by mu times the normal impulse.
            const Eigen::Vector3d vc = v + w.cross(c.arm);
            const Eigen::Vector3d vt = vc - c.normal.dot(vc) * c.normal;
            const double speed = vt.norm();
            if (speed < 1e-12) continue;
            const Eigen::Vector3d t = vt / speed;
            const double limit = c.friction * c.normalImpulse;
            applyImpulse(c.arm, std::clamp(-effectiveMass(c.arm, t) * speed, -limit, limit) * t);
        }
    }
    // Position correction per collider along its deepest contact's normal; velocities are
    // untouched, so it adds no kinetic energy.
    const double slop = 0.01 * body.voxelSizeM;
    for (int collider = -1; collider < static_cast<int>(world.colliders.size()); ++collider) {
        const Contact* deepest = nullptr;
        for (const Contact& c : contacts)
            if (c.collider == collider && (!deepest || c.depth > deepest->depth)) deepest = &c;
        if (deepest && deepest->depth > slop) body.positionM += (deepest->depth - slop) * deepest->normal;
    }
    return static_cast<int>(contacts.size());
}

void updateSleep(Body& body, const SleepSettings& settings, double dt)
{
    if (!settings.enabled || body.anchored) return;
    if (body.linearVelocityMS.norm() < settings.linearSpeedMS && body.angularVelocityRadS.norm() < settings.angularSpeedRadS) {
        body.restTimeS += dt;
        if (body.restTimeS >= settings.timeS) {
            body.asleep = true;
            body.linearVelocityMS.setZero();
            body.angularVelocityRadS.setZero();
        }
    } else {
        body.restTimeS = 0.0;
    }
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
