#include "BenchCollisions.h"

#include <spall/sim/Simulation.h>
#include <spall/dynamics/DebrisScenes.h>
#include <spall/voxel/VdbIo.h>

#ifdef SPALL_WITH_BULLET
#include <btBulletDynamicsCommon.h>
#endif

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace spall {

namespace {

constexpr double kVoxelSizeM = 0.05;
constexpr double kStepS = 1.0 / 240;
constexpr int kFragmentEdge = 4;            ///< 56 boundary voxels per fragment
constexpr double kBudgetPerMeasurementS = 0.6;
/// Fragments fly out at up to this speed: under half a voxel per step, as spall's own step rule keeps them.
constexpr double kExplosionSpeedMS = 5.0;
constexpr double kLongestStepS = 3.0;       ///< sizes whose steps would take longer are skipped
/// The pile is measured resting: spall settles it this long first, and every method (Bullet
/// included) starts from that same state. Timing the first steps instead measures fragments still
/// landing, with fewer contacts than the pile has at rest.
constexpr double kSettleS = 0.25;

using Clock = std::chrono::steady_clock;

/// Steps per second of `step`, after two warm-up steps, over about the time budget.
double measureStepsPerSecond(const std::function<void()>& step)
{
    step();
    step();
    const auto start = Clock::now();
    int steps = 0;
    double elapsed = 0;
    while (steps < 3 || (elapsed < kBudgetPerMeasurementS && steps < 400)) {
        step();
        ++steps;
        elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    }
    return steps / elapsed;
}

#ifdef SPALL_WITH_BULLET
/// The same scene in Bullet: each fragment a compound of one box per voxel, the ground a plane,
/// the container walls static boxes; same time step, solver sweeps, friction and restitution, no
/// sleeping.
class BulletWorld {
public:
    explicit BulletWorld(const DebrisScene& scene)
        : mDispatcher(&mConfiguration), mWorld(&mDispatcher, &mBroadphase, &mSolver, &mConfiguration),
          mVoxel(btVector3(0.5 * kVoxelSizeM, 0.5 * kVoxelSizeM, 0.5 * kVoxelSizeM))
    {
        const Eigen::Vector3d g = scene.world.gravityMS2;
        mWorld.setGravity(btVector3(g.x(), g.y(), g.z()));
        mWorld.getSolverInfo().m_numIterations = CollisionSettings().solverIterations;  // same sweeps as spall's
        addStatic(std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), 0.0), btTransform::getIdentity(), scene.world.ground.friction,
                  scene.world.ground.restitution);
        for (const StaticBox& box : scene.world.colliders) {
            btTransform pose;
            pose.setIdentity();
            pose.setOrigin(btVector3(box.centreM.x(), box.centreM.y(), box.centreM.z()));
            pose.setRotation(btQuaternion(box.orientation.x(), box.orientation.y(), box.orientation.z(), box.orientation.w()));
            addStatic(std::make_unique<btBoxShape>(btVector3(box.halfExtentM.x(), box.halfExtentM.y(), box.halfExtentM.z())), pose,
                      box.friction, box.restitution);
        }
        for (const Body& body : scene.bodies) {
            auto compound = std::make_unique<btCompoundShape>();
            for (auto it = body.grid->cbeginValueOn(); it; ++it) {
                const Eigen::Vector3d offset = body.voxelOffsetM(it.getCoord());
                btTransform child;
                child.setIdentity();
                child.setOrigin(btVector3(offset.x(), offset.y(), offset.z()));
                compound->addChildShape(child, &mVoxel);
            }
            btVector3 inertia(0, 0, 0);
            compound->calculateLocalInertia(body.mass.massKg, inertia);
            btTransform pose;
            pose.setIdentity();
            pose.setOrigin(btVector3(body.motion.positionM.x(), body.motion.positionM.y(), body.motion.positionM.z()));
            pose.setRotation(btQuaternion(body.motion.orientation.x(), body.motion.orientation.y(), body.motion.orientation.z(), body.motion.orientation.w()));
            mMotion.push_back(std::make_unique<btDefaultMotionState>(pose));
            btRigidBody::btRigidBodyConstructionInfo info(body.mass.massKg, mMotion.back().get(), compound.get(), inertia);
            info.m_friction = 0.6;
            info.m_restitution = 0.2;
            auto rigid = std::make_unique<btRigidBody>(info);
            rigid->setLinearVelocity(btVector3(body.motion.linearVelocityMS.x(), body.motion.linearVelocityMS.y(), body.motion.linearVelocityMS.z()));
            rigid->setAngularVelocity(btVector3(body.motion.angularVelocityRadS.x(), body.motion.angularVelocityRadS.y(), body.motion.angularVelocityRadS.z()));
            rigid->setActivationState(DISABLE_DEACTIVATION);
            mWorld.addRigidBody(rigid.get());
            mShapes.push_back(std::move(compound));
            mBodies.push_back(std::move(rigid));
        }
    }
    ~BulletWorld()
    {
        for (auto& b : mBodies) mWorld.removeRigidBody(b.get());
    }
    void step() { mWorld.stepSimulation(kStepS, 0, kStepS); }

private:
    void addStatic(std::unique_ptr<btCollisionShape> shape, const btTransform& pose, double friction, double restitution)
    {
        mMotion.push_back(std::make_unique<btDefaultMotionState>(pose));
        btRigidBody::btRigidBodyConstructionInfo info(0.0, mMotion.back().get(), shape.get());
        info.m_friction = friction;
        info.m_restitution = restitution;
        mBodies.push_back(std::make_unique<btRigidBody>(info));
        mWorld.addRigidBody(mBodies.back().get());
        mShapes.push_back(std::move(shape));
    }

    btDefaultCollisionConfiguration mConfiguration;
    btCollisionDispatcher mDispatcher;
    btDbvtBroadphase mBroadphase;
    btSequentialImpulseConstraintSolver mSolver;
    btDiscreteDynamicsWorld mWorld;
    btBoxShape mVoxel;
    std::vector<std::unique_ptr<btCollisionShape>> mShapes;
    std::vector<std::unique_ptr<btDefaultMotionState>> mMotion;
    std::vector<std::unique_ptr<btRigidBody>> mBodies;
};
#endif

struct Row {
    std::string scene, method;
    long boundaryVoxels;
    double stepsPerS;  ///< 0: skipped (over the time limit)
};

/// Steps per second of one collision method on a scene's bodies.
double measureMethod(const DebrisScene& base, const std::string& method, const SleepSettings& noSleep)
{
    if (method == "bullet") {
#ifdef SPALL_WITH_BULLET
        BulletWorld world(base);
        return measureStepsPerSecond([&] { world.step(); });
#endif
    }
    CollisionSettings collisions;
    collisions.method = parseEnum<CollisionMethod>(method);
    Simulation sim = rigidBodySimulation(base.bodies, base.world, collisions, noSleep, kStepS, true);
    return measureStepsPerSecond([&] { sim.step(); });
}

/// One scene ("pile" or "explosion") at growing sizes, every method; a method whose next step
/// would exceed kLongestStepS (pairwise grows with the square of the voxels) is skipped from then on.
void benchScene(const std::string& scene, const std::vector<std::string>& methods, long maxBoundaryVoxels, bool verbose, std::vector<Row>& rows)
{
    SleepSettings noSleep;
    noSleep.enabled = false;
    // Fragment counts: one small fragment, then about 10^2 ... 10^6 boundary voxels.
    std::vector<std::pair<int, int>> sizes = {{1, 2}};  // (fragments, edge)
    for (long target = 100; target <= 1'000'000; target *= 10) sizes.push_back({static_cast<int>((target + 28) / 56), kFragmentEdge});
    std::map<std::string, double> lastStepS;
    std::map<std::string, long> lastVoxels;
    for (const auto& [fragments, edge] : sizes) {
        DebrisScene base = scene == "pile" ? makeDebrisPile(fragments, edge, kVoxelSizeM, 1)
                                           : makeExplosionCloud(fragments, edge, kVoxelSizeM, kExplosionSpeedMS, 1);
        if (base.boundaryVoxels > maxBoundaryVoxels) break;
        if (scene == "pile") {
            Simulation settle = rigidBodySimulation(base.bodies, base.world, CollisionSettings(), noSleep, kStepS, true);
            settle.advanceTo(kSettleS);
            base.bodies = settle.bodies();
        }
        for (const std::string& method : methods) {
            if (method == "bullet" && scene != "pile") continue;
            if (lastStepS.count(method)) {
                const double growth = static_cast<double>(base.boundaryVoxels) / lastVoxels[method];
                const double predicted = lastStepS[method] * (method == "pairwise" ? growth * growth : growth);
                if (lastStepS[method] == 0 || predicted > kLongestStepS) {
                    rows.push_back({scene, method, base.boundaryVoxels, 0.0});
                    lastStepS[method] = 0;
                    continue;
                }
            }
            const double stepsPerS = measureMethod(base, method, noSleep);
            rows.push_back({scene, method, base.boundaryVoxels, stepsPerS});
            lastStepS[method] = 1.0 / stepsPerS;
            lastVoxels[method] = base.boundaryVoxels;
            if (verbose)
                std::fprintf(stderr, "  %-9s %-11s %8ld boundary voxels: %10.1f steps/s\n", scene.c_str(), method.c_str(), base.boundaryVoxels,
                             stepsPerS);
        }
    }
}

/// One line per scene and size, a column per method, and the ratios.
void printCollisionTable(const std::vector<Row>& rows)
{
    auto find = [&](const Row& r, const std::string& method) -> double {
        for (const Row& o : rows)
            if (o.scene == r.scene && o.boundaryVoxels == r.boundaryVoxels && o.method == method) return o.stepsPerS;
        return 0.0;
    };
    std::printf("Steps per second (time step %.4g s, voxel %.3g m, fragments of %d^3 voxels, sleep off, the pile settled for\n"
                "%.2g s first; '-' = skipped, would exceed %.0f s per step). Ratios: against pairwise in the same run; x bullet:\n"
                "tree lookup / Bullet.\n",
                kStepS, kVoxelSizeM, kFragmentEdge, kSettleS, kLongestStepS);
    std::printf("%-10s %10s %12s %12s %12s %12s %12s %10s %10s\n", "scene", "boundary", "none", "pairwise", "buckets", "tree-lookup",
                "bullet", "tree/pair", "tree/bullet");
    for (const Row& r : rows) {
        if (r.method != "none") continue;
        auto cell = [&](const std::string& m) {
            const double v = find(r, m);
            char buf[32];
            if (v > 0) std::snprintf(buf, sizeof buf, "%.1f", v);
            else std::snprintf(buf, sizeof buf, "-");
            return std::string(buf);
        };
        const double tree = find(r, "tree-lookup"), pair = find(r, "pairwise"), bullet = find(r, "bullet");
        char vsPair[32] = "-", vsBullet[32] = "-";
        if (tree > 0 && pair > 0) std::snprintf(vsPair, sizeof vsPair, "%.1fx", tree / pair);
        if (tree > 0 && bullet > 0) std::snprintf(vsBullet, sizeof vsBullet, "%.1fx", tree / bullet);
        std::printf("%-10s %10ld %12s %12s %12s %12s %12s %10s %10s\n", r.scene.c_str(), r.boundaryVoxels, cell("none").c_str(),
                    cell("pairwise").c_str(), cell("buckets").c_str(), cell("tree-lookup").c_str(), cell("bullet").c_str(), vsPair, vsBullet);
    }
}

}  // namespace

int benchCollisions(bool json, long maxBoundaryVoxels)
{
    initialiseOpenVdb();
    std::vector<std::string> methods = {"none", "pairwise", "buckets", "tree-lookup"};
#ifdef SPALL_WITH_BULLET
    methods.push_back("bullet");
#endif
    std::vector<Row> rows;
    for (const std::string scene : {"pile", "explosion"}) benchScene(scene, methods, maxBoundaryVoxels, !json, rows);
    if (!json) {
        printCollisionTable(rows);
        return 0;
    }
    nlohmann::json out = nlohmann::json::array();
    for (const Row& r : rows)
        out.push_back({{"scene", r.scene}, {"method", r.method}, {"boundary_voxels", r.boundaryVoxels},
                       {"steps_per_s", r.stepsPerS > 0 ? nlohmann::json(r.stepsPerS) : nlohmann::json(nullptr)}});
    std::cout << out.dump(1) << "\n";
    return 0;
}

}  // namespace spall
