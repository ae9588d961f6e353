// spall benchmarks (Google Benchmark). Each benchmark has a baseline run in the same process;
// after the run a table prints each one's time as a ratio to its baseline.
//   build/spall_bench                          all
//   build/spall_bench --benchmark_filter=Label  one group
#include <spall/blast/Blast.h>
#include <spall/dynamics/Integrate.h>
#include <spall/dynamics/NarrowPhase.h>
#include <spall/dynamics/StaticContacts.h>
#include <spall/fracture/Fracture.h>
#include <spall/voxel/VdbIo.h>
#include <spall/lattice/Lattice.h>
#include <spall/core/Parallel.h>
#include <spall/loads/BlastLoads.h>
#include <spall/output/FrameWriter.h>
#include <spall/voxel/Components.h>
#include <spall/render/Render.h>
#include <spall/voxel/Voxelise.h>

#include <benchmark/benchmark.h>
#include <openvdb/tools/RayTracer.h>
#include <openvdb/tools/TopologyToLevelSet.h>
#include <openvdb/tree/LeafManager.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <random>
#include <string>

using namespace spall;

namespace {

LinkGrid::Ptr block(int n)
{
    initialiseOpenVdb();
    LinkGrid::Ptr g = LinkGrid::create(0);
    g->tree().denseFill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(n - 1)), 0, true);
    linkAllNeighbours(*g);
    return g;
}

/// The block cut into cubes of `piece` voxels on a side.
LinkGrid::Ptr cutBlock(int n, int piece)
{
    LinkGrid::Ptr g = block(n);
    openvdb::tree::LeafManager<LinkTree> leaves(g->tree());
    leaves.foreach ([piece](LinkLeaf& leaf, size_t) {
        for (auto it = leaf.beginValueOn(); it; ++it) {
            const openvdb::Coord c = it.getCoord();
            int32_t bits = *it;
            for (int axis = 0; axis < 3; ++axis) {
                if (c[axis] % piece == piece - 1) bits &= ~(1 << (2 * axis + 1));
                if (c[axis] % piece == 0) bits &= ~(1 << (2 * axis));
            }
            it.setValue(bits);
        }
    });
    return g;
}

/// Baseline: read and write every voxel's value once, in parallel over leaves.
void trivialPass(LinkGrid& grid)
{
    openvdb::tree::LeafManager<LinkTree> leaves(grid.tree());
    leaves.foreach ([](LinkLeaf& leaf, size_t) {
        for (auto it = leaf.beginValueOn(); it; ++it) it.setValue(*it ^ 0x80);
    });
}

void BM_Label_TrivialPass256(benchmark::State& state)
{
    auto g = block(256);
    for (auto _ : state) trivialPass(*g);
    state.counters["voxels_per_s"] = benchmark::Counter(double(g->activeVoxelCount()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Label_TrivialPass256)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Label_Components256Whole(benchmark::State& state)
{
    auto g = block(256);
    for (auto _ : state) benchmark::DoNotOptimize(labelComponents(*g).componentCount);
    state.counters["components"] = labelComponents(*g).componentCount;
    state.counters["voxels_per_s"] = benchmark::Counter(double(g->activeVoxelCount()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Label_Components256Whole)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Label_Components256Cut(benchmark::State& state)
{
    auto g = cutBlock(256, 12);  // 22^3 = 10648 pieces
    for (auto _ : state) benchmark::DoNotOptimize(labelComponents(*g).componentCount);
    state.counters["components"] = labelComponents(*g).componentCount;
    state.counters["voxels_per_s"] = benchmark::Counter(double(g->activeVoxelCount()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Label_Components256Cut)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Voxelise_PrimitiveBox(benchmark::State& state)
{
    initialiseOpenVdb();
    VoxeliseSettings s;
    s.voxelSizeM = 0.01;
    int64_t voxels = 0;
    for (auto _ : state) voxels = voxelisePrimitive({PrimitiveShape::Box, {1.0, 1.0, 1.0}}, s).voxelCount;
    state.counters["voxels_per_s"] = benchmark::Counter(double(voxels), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Voxelise_PrimitiveBox)->Unit(benchmark::kMillisecond)->UseRealTime();

/// The same closed mesh through each inside test: the level set is the baseline.
template <InsideTest kTest>
void BM_Voxelise_TorusMesh(benchmark::State& state)
{
    initialiseOpenVdb();
    const TriangleMesh mesh = loadMesh(SPALL_SOURCE_DIR "/assets/meshes/torus.obj");
    VoxeliseSettings s;
    s.voxelSizeM = 0.005;
    s.insideTest = kTest;
    int64_t voxels = 0;
    for (auto _ : state) voxels = voxeliseMesh(mesh, s, "torus").voxelCount;
    state.counters["voxels_per_s"] = benchmark::Counter(double(voxels), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Voxelise_TorusMesh<InsideTest::LevelSet>)->Name("BM_Voxelise_TorusLevelSet")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Voxelise_TorusMesh<InsideTest::WindingNumber>)->Name("BM_Voxelise_TorusWindingNumber")->Unit(benchmark::kMillisecond)->UseRealTime();

// Pressure evaluations: the table (hot path) against the direct fits (polynomials, a log and
// pow per quantity, a decay-coefficient solve).
constexpr int kPressureSamples = 1 << 16;

void BM_Pressure_DirectFits(benchmark::State& state)
{
    double sum = 0;
    for (auto _ : state) {
        for (int i = 0; i < kPressureSamples; i += 64) {
            const double r = 1.0 + 20.0 * i / kPressureSamples;
            const BlastParameters p = blastParameters(BlastDataset::KingeryBulmash, BurstType::FreeAir, 10.0, r);
            sum += overpressureAt(p, p.arrivalTimeS + 0.3 * p.positiveDurationS);
        }
    }
    benchmark::DoNotOptimize(sum);
    state.counters["evals_per_s"] = benchmark::Counter(kPressureSamples / 64, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Pressure_DirectFits)->Unit(benchmark::kMicrosecond)->UseRealTime();

void BM_Pressure_Table(benchmark::State& state)
{
    BlastSettings bs;
    bs.tableNodesPerDecade = static_cast<int>(state.range(0));
    const BlastField field({Charge{Eigen::Vector3d::Zero(), 10.0, 0.0, BurstType::FreeAir}}, bs);
    const double t = 0.02;
    const auto windows = field.openWindows(t);
    double sum = 0;
    for (auto _ : state) {
        for (int i = 0; i < kPressureSamples; ++i)
            sum += field.sample(Eigen::Vector3d(1.0 + 20.0 * i / kPressureSamples, 0.1, 0.2), t, windows).overpressurePa;
    }
    benchmark::DoNotOptimize(sum);
    state.counters["evals_per_s"] = benchmark::Counter(kPressureSamples, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Pressure_Table)->Arg(16)->Arg(64)->Arg(128)->Arg(512)->Unit(benchmark::kMicrosecond)->UseRealTime();

// The same points from a snapshot of the field at that instant (what link loading queries).
void BM_Pressure_Snapshot(benchmark::State& state)
{
    BlastSettings bs;
    const BlastField field({Charge{Eigen::Vector3d::Zero(), 10.0, 0.0, BurstType::FreeAir}}, bs);
    const PressureSnapshot snapshot(field, 0.02, 0.0);
    double sum = 0;
    for (auto _ : state) {
        for (int i = 0; i < kPressureSamples; ++i) sum += snapshot.sample(Eigen::Vector3d(1.0 + 20.0 * i / kPressureSamples, 0.1, 0.2)).overpressurePa;
    }
    benchmark::DoNotOptimize(sum);
    state.counters["evals_per_s"] = benchmark::Counter(kPressureSamples, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Pressure_Snapshot)->Unit(benchmark::kMicrosecond)->UseRealTime();

// Link loading: a 256^3 block entirely inside the open window, against the trivial pass. The
// worst case for the loading pass: the pressure everywhere lies within the links' spread of
// limits, so no leaf can be skipped and every link needs its own limit. The first pass breaks
// the links below the pressure; every timed pass after it evaluates all the rest and breaks none
// (same time, same limits), so each iteration does the same work.
void BM_Loading_Links256(benchmark::State& state)
{
    auto g = block(256);
    Body body = makeBody(g, 0.01, 2000.0);
    body.motion.positionM = Eigen::Vector3d(0, 0, 0);
    BlastSettings bs;
    // 100 kg 40 m away: the front has just passed the far corner (41.3 m), and the pressure
    // across the block varies by less than the links' spread of limits (a factor of 3).
    const BlastField field({Charge{Eigen::Vector3d(-40.0, 0, 0), 100.0, 0.0, BurstType::FreeAir}}, bs);
    const BlastParameters far = field.tableParameters(0, 41.4);
    const PressureSnapshot pressure(field, far.arrivalTimeS + 0.05 * far.positiveDurationS, 0.0);
    double lowestPa = std::numeric_limits<double>::infinity();
    for (double r = 38.6; r <= 41.4; r += 0.01) lowestPa = std::min(lowestPa, pressure.overpressurePa(0, r));
    Material m = findMaterialPreset("reinforced-concrete");
    m.yieldVariation = 0.5;
    m.meanYieldPa = 0.99 * lowestPa / (1.0 - m.yieldVariation);
    FractureSettings fs;
    fs.weakening = false;
    fs.orientation = false;
    const LoadResult first = loadLinks(body, m, pressure, 1e-6, fs, 1);
    if (first.skippedLeaves != 0) state.SkipWithError("leaves were skipped");
    for (auto _ : state) {
        const LoadResult again = loadLinks(body, m, pressure, 1e-6, fs, 1);
        if (again.brokenLinks != 0 || again.skippedLeaves != 0) state.SkipWithError("the timed passes must repeat the same work");
    }
    state.counters["links_per_s"] = benchmark::Counter(double(countLinks(*g)), benchmark::Counter::kIsIterationInvariantRate);
    state.counters["broken_first_pass"] = double(first.brokenLinks);
}
BENCHMARK(BM_Loading_Links256)->Unit(benchmark::kMillisecond)->UseRealTime();

// Previews of a 100^3 block (1 M voxels) at 960x540: spall's rasteriser of exposed faces against
// OpenVDB's level-set ray tracer (which first needs a level set of the voxels), same camera.
openvdb::FloatGrid::Ptr renderBlock()
{
    initialiseOpenVdb();
    auto g = openvdb::FloatGrid::create(0.0f);
    g->setTransform(openvdb::math::Transform::createLinearTransform(0.01));
    g->tree().denseFill(openvdb::CoordBBox(openvdb::Coord(-50, -50, 0), openvdb::Coord(49, 49, 99)), 1.0f, true);
    g->tree().voxelizeActiveTiles();
    return g;
}

/// The loads pass over the exposed faces of 1000 one-voxel fragments (6000 faces) 4 m from
/// 20 kg, a step of 20 us just behind the front (every face loaded), per model; and with a 2 m
/// barrier between them and the charge, so that every face takes the diffracted wave. Baseline:
/// the paper's rule with an ideal-gas reflection (spall's default before blast engineering).
void loadsPass(benchmark::State& state, LoadModel model, bool behindABarrier = false)
{
    initialiseOpenVdb();
    const BlastField field({Charge{Eigen::Vector3d::Zero(), 20.0, 0.0, BurstType::Surface}}, BlastSettings());
    std::vector<Body> bodies;
    for (int i = 0; i < 1000; ++i) {
        Body b = makeBody(block(1), 0.1, 1800.0);
        b.motion.positionM = Eigen::Vector3d(4.0 + 0.1 * (i % 10), 0.1 * ((i / 10) % 10), 0.1 * (i / 100));
        bodies.push_back(std::move(b));
    }
    const double t = field.tableParameters(0, 4.5).arrivalTimeS + 1e-4;
    const std::vector<OpenWindow> windows = field.openWindows(t);
    StaticWorld geometry;
    geometry.ground = GroundPlane{true, Eigen::Vector3d::UnitZ(), 0.0};
    if (behindABarrier)
        geometry.boxes.push_back({Eigen::Vector3d(3.5, 0.5, 1.0), Eigen::Vector3d(0.05, 5.0, 1.0), Eigen::Quaterniond::Identity()});
    const BlastLoads loads(field, windows, LoadSettings{model}, geometry);
    const std::vector<char> loaded(bodies.size(), 1);
    for (auto _ : state) benchmark::DoNotOptimize(loads.stepWrenches(bodies, loaded, t, 2e-5));
    state.counters["faces_per_s"] = benchmark::Counter(6000.0, benchmark::Counter::kIsIterationInvariantRate);
}
void BM_Loads_PaperReflected(benchmark::State& state) { loadsPass(state, LoadModel::PaperReflected); }
BENCHMARK(BM_Loads_PaperReflected)->Unit(benchmark::kMicrosecond)->UseRealTime();
void BM_Loads_BlastEngineering(benchmark::State& state) { loadsPass(state, LoadModel::BlastEngineering); }
BENCHMARK(BM_Loads_BlastEngineering)->Unit(benchmark::kMicrosecond)->UseRealTime();
void BM_Loads_BlastEngineeringBehindABarrier(benchmark::State& state) { loadsPass(state, LoadModel::BlastEngineering, true); }
BENCHMARK(BM_Loads_BlastEngineeringBehindABarrier)->Unit(benchmark::kMicrosecond)->UseRealTime();

/// One wall's step of face loads, as the deformable phase asks for them every lattice step: a
/// 0.1 × 1 × 1 m wall of 1 cm voxels (24 000 exposed faces) 4 m from 20 kg, a step of 20 us just
/// behind the front, per model (baseline: the paper's rule, one pressure sample a face).
void wallLoadsStep(benchmark::State& state, LoadModel model)
{
    initialiseOpenVdb();
    LinkGrid::Ptr grid = LinkGrid::create(0);
    grid->tree().denseFill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(9, 99, 99)), 0, true);
    linkAllNeighbours(*grid);
    Body wall = makeBody(grid, 0.01, 1800.0);
    wall.motion.positionM = Eigen::Vector3d(4.05, 0.0, 0.5);
    const BlastField field({Charge{Eigen::Vector3d::Zero(), 20.0, 0.0, BurstType::Surface}}, BlastSettings());
    const double t = field.tableParameters(0, 4.0).arrivalTimeS + 1e-4;
    const std::vector<OpenWindow> windows = field.openWindows(t);
    const StaticWorld nothingElse;  // BlastLoads keeps references to its windows and geometry
    const BlastLoads loads(field, windows, LoadSettings{model}, nothingElse);
    for (auto _ : state) benchmark::DoNotOptimize(loads.stepWrench(wall, t, 2e-5));
    state.counters["faces_per_s"] = benchmark::Counter(double(wall.exposedFaces.size()), benchmark::Counter::kIsIterationInvariantRate);
}
void BM_Loads_WallPaperReflected(benchmark::State& state) { wallLoadsStep(state, LoadModel::PaperReflected); }
BENCHMARK(BM_Loads_WallPaperReflected)->Unit(benchmark::kMicrosecond)->UseRealTime();
void BM_Loads_WallBlastEngineering(benchmark::State& state) { wallLoadsStep(state, LoadModel::BlastEngineering); }
BENCHMARK(BM_Loads_WallBlastEngineering)->Unit(benchmark::kMicrosecond)->UseRealTime();

void BM_Render_Rasteriser(benchmark::State& state)
{
    const auto grid = renderBlock();
    const RenderSettings settings;
    const std::vector<FragmentRef> fragments = {{grid.get(), grid->transform().copy(), 1}};
    const Camera camera = frameCamera({fragments}, settings);
    for (auto _ : state) benchmark::DoNotOptimize(renderFragments(fragments, camera, settings).pixels().data());
    state.counters["voxels_per_s"] = benchmark::Counter(double(grid->activeVoxelCount()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Render_Rasteriser)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Render_OpenVdbRayTracer(benchmark::State& state)
{
    const auto grid = renderBlock();
    const RenderSettings settings;
    const std::vector<FragmentRef> fragments = {{grid.get(), grid->transform().copy(), 1}};
    const Camera camera = frameCamera({fragments}, settings);
    for (auto _ : state) {
        auto levelSet = openvdb::tools::topologyToLevelSet(*grid);
        openvdb::tools::Film film(settings.width, settings.height);
        openvdb::tools::PerspectiveCamera cam(film, openvdb::Vec3R(0.0),
                                              openvdb::Vec3R(camera.eyeM.x(), camera.eyeM.y(), camera.eyeM.z()), 50.0, 41.2136 * 1.6);
        cam.lookAt(openvdb::Vec3R(camera.targetM.x(), camera.targetM.y(), camera.targetM.z()), openvdb::Vec3R(0, 0, 1));
        openvdb::tools::DiffuseShader<> shader;
        openvdb::tools::rayTrace(*levelSet, shader, cam);
        benchmark::DoNotOptimize(film.pixels());
    }
    state.counters["voxels_per_s"] = benchmark::Counter(double(grid->activeVoxelCount()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Render_OpenVdbRayTracer)->Unit(benchmark::kMillisecond)->UseRealTime();

/// The deformable phase's lattice: a block `edge` particles a side, set vibrating; the baseline is
/// a pass that moves every particle by its velocity over the same arrays. 60^3 (216 000 particles)
/// is the size DESIGN.md's speed anchor uses for ESyS-Particle and Yade; 24^3 fits in a core's
/// cache, 100^3 (a million particles) is far out of it (issue 49's goals at 60^3 and 100^3).
Lattice vibratingBlock(int edge = 60, bool crushes = true)
{
    Body body = makeBody(block(edge), 0.01, 2400.0);
    Material concrete = findMaterialPreset("concrete");
    if (!crushes) concrete.compressiveStrengthPa = 0.0;
    Lattice lattice = Lattice::fromBody(body, concrete);  // damped at the material's ratio, as in a run
    std::mt19937 random(3);
    std::normal_distribution<double> normal(0.0, 0.01);
    for (Eigen::Vector3d& v : lattice.state.velocityMS) v = Eigen::Vector3d(normal(random), normal(random), normal(random));
    return lattice;
}

void BM_Lattice_TrivialPass(benchmark::State& state)
{
    Lattice lattice = vibratingBlock(int(state.range(0)));
    const double dt = lattice.stableTimeStepS();
    for (auto _ : state) {
        forEachIndex(lattice.particleCount(), [&](size_t p) { lattice.state.positionM[p] += dt * lattice.state.velocityMS[p]; }, kCheapGrain);
        benchmark::DoNotOptimize(lattice.state.positionM.data());
    }
    state.counters["particle_steps_per_s"] = benchmark::Counter(double(lattice.particleCount()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Lattice_TrivialPass)->Arg(24)->Arg(60)->Arg(100)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Lattice_Step(benchmark::State& state)
{
    Lattice lattice = vibratingBlock(int(state.range(0)));
    const double dt = lattice.stableTimeStepS();
    for (auto _ : state) lattice.step(dt);
    state.counters["particle_steps_per_s"] = benchmark::Counter(double(lattice.particleCount()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Lattice_Step)->Arg(24)->Arg(60)->Arg(100)->Unit(benchmark::kMillisecond)->UseRealTime();

/// The block with every bond halfway along its softening line: a cracked body vibrating on its
/// bonds' secant stiffness, as a piece is after the blast. The batches take these bonds too
/// (BondStrainRun::steady); one at a time, each takes the one-bond path.
Lattice crackedBlock(int edge)
{
    Lattice lattice = vibratingBlock(edge);
    for (size_t b = 0; b < lattice.bondCount(); ++b) {
        BondHistory& history = lattice.state.bondHistory[b];
        const LatticeStiffness::Strength& strength = lattice.model().stiffness.strength[lattice.model().bonds[b].strengthClass];
        const double scale = history.strengthScale * history.strengthFactor;
        const double peakM = scale * strength.peakStretchM, endM = strength.zeroTractionStretchM / scale;
        history.maxEquivalentStretchM = peakM + 0.5 * (endM - peakM);
    }
    lattice.refreshForces();
    return lattice;
}

void stepCrackedBlock(benchmark::State& state, bool batched)
{
    Lattice lattice = crackedBlock(int(state.range(0)));
    lattice.batchSteadyBonds(batched);
    const double dt = lattice.stableTimeStepS();
    for (auto _ : state) lattice.step(dt);
    state.counters["particle_steps_per_s"] = benchmark::Counter(double(lattice.particleCount()), benchmark::Counter::kIsIterationInvariantRate);
    state.counters["bonds_batched"] = double(lattice.bondsBatchedInLastPass());
}
void BM_Lattice_StepCracked(benchmark::State& state) { stepCrackedBlock(state, true); }
void BM_Lattice_StepCrackedOneBondAtATime(benchmark::State& state) { stepCrackedBlock(state, false); }
BENCHMARK(BM_Lattice_StepCracked)->Arg(60)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Lattice_StepCrackedOneBondAtATime)->Arg(60)->Unit(benchmark::kMillisecond)->UseRealTime();

/// Building the block's lattice (its strength scatter included), which a body pays once when it
/// enters the phase: its ratio to a step says how many steps it costs.
void BM_Lattice_Build(benchmark::State& state)
{
    for (auto _ : state) benchmark::DoNotOptimize(vibratingBlock().particleCount());
}
BENCHMARK(BM_Lattice_Build)->Unit(benchmark::kMillisecond)->UseRealTime();

/// The same with every bond measured one at a time (Lattice::batchSteadyBonds off): what
/// measuring the elastic bonds' laws side by side saves.
void BM_Lattice_StepOneBondAtATime(benchmark::State& state)
{
    Lattice lattice = vibratingBlock(int(state.range(0)));
    lattice.batchSteadyBonds(false);
    const double dt = lattice.stableTimeStepS();
    for (auto _ : state) lattice.step(dt);
    state.counters["particle_steps_per_s"] = benchmark::Counter(double(lattice.particleCount()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Lattice_StepOneBondAtATime)->Arg(24)->Arg(60)->Unit(benchmark::kMillisecond)->UseRealTime();

/// The same without crushing: what crushing's reading of each compressed bond costs.
void BM_Lattice_StepWithoutCrushing(benchmark::State& state)
{
    Lattice lattice = vibratingBlock(60, false);
    const double dt = lattice.stableTimeStepS();
    for (auto _ : state) lattice.step(dt);
    state.counters["particle_steps_per_s"] = benchmark::Counter(double(lattice.particleCount()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Lattice_StepWithoutCrushing)->Unit(benchmark::kMillisecond)->UseRealTime();

/// 3000 single-voxel bodies in flight, one integrate phase: without and with the air's drag.
void integrateFlyingVoxels(benchmark::State& state, AirDrag drag)
{
    initialiseOpenVdb();
    std::vector<Body> bodies;
    for (int i = 0; i < 3000; ++i) {
        bodies.push_back(makeBody(block(1), 0.05, 1800.0));
        bodies.back().motion.positionM = Eigen::Vector3d(0.1 * (i % 50), 0.1 * (i / 50), 2.0);
        bodies.back().motion.linearVelocityMS = Eigen::Vector3d(20.0 + i % 7, 3.0, 10.0);
    }
    const std::vector<Wrench> blast(bodies.size());
    WorldSettings world;
    world.airDrag = drag;
    const Air air = airOf(Atmosphere{});
    for (auto _ : state) integrateBodies(bodies, blast, world, air, Integrator::SemiImplicitEuler, 0.0, 1e-4);
}
void BM_Integrate_Flight(benchmark::State& state) { integrateFlyingVoxels(state, AirDrag::None); }
BENCHMARK(BM_Integrate_Flight)->Unit(benchmark::kMicrosecond)->UseRealTime();
void BM_Integrate_FlightWithAirDrag(benchmark::State& state) { integrateFlyingVoxels(state, AirDrag::HaiderLevenspiel); }
BENCHMARK(BM_Integrate_FlightWithAirDrag)->Unit(benchmark::kMicrosecond)->UseRealTime();

/// A 2 × 1 × 0.1 m slab of 1 cm voxels (200 000) resting flat, its centre `heightM` up, turned
/// a little about z so that its voxels do not line up with another's.
Body restingSlab(double heightM, double turnRad)
{
    initialiseOpenVdb();
    LinkGrid::Ptr g = LinkGrid::create(0);
    g->tree().denseFill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(199, 99, 9)), 0, true);
    linkAllNeighbours(*g);
    Body slab = makeBody(g, 0.01, 1800.0);
    slab.motion.positionM = Eigen::Vector3d(0.0, 0.0, heightM);
    slab.motion.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(turnRad, Eigen::Vector3d::UnitZ()));
    return slab;
}

/// Baseline: each boundary voxel's centre in the world and its height, the least a search of
/// a body's contacts must do.
void BM_Contacts_BoundaryPass(benchmark::State& state)
{
    const Body slab = restingSlab(0.049, 0.0);
    for (auto _ : state) {
        double sum = 0.0;
        for (const openvdb::Coord& v : slab.boundaryVoxels) sum += slab.voxelWorldM(v).z();
        benchmark::DoNotOptimize(sum);
    }
}
BENCHMARK(BM_Contacts_BoundaryPass)->Unit(benchmark::kMicrosecond)->UseRealTime();

/// The slab lying on the ground, a millimetre into it: 80 000 corners, reduced to four.
void BM_Contacts_SlabOnGround(benchmark::State& state)
{
    const Body slab = restingSlab(0.049, 0.0);
    WorldSettings world;
    for (auto _ : state) benchmark::DoNotOptimize(findStaticContacts(slab, world));
}
BENCHMARK(BM_Contacts_SlabOnGround)->Unit(benchmark::kMicrosecond)->UseRealTime();

/// A second slab lying on the first (turned 0.1 rad): their voxel pairs, reduced to a manifold.
void BM_Contacts_SlabOnSlab(benchmark::State& state)
{
    const std::vector<Body> bodies = {restingSlab(0.05, 0.0), restingSlab(0.1495, 0.1)};
    for (auto _ : state) benchmark::DoNotOptimize(findBodyContacts(bodies, CollisionMethod::TreeLookup));
}
BENCHMARK(BM_Contacts_SlabOnSlab)->Unit(benchmark::kMicrosecond)->UseRealTime();

/// A frame of a cracked wall at 1 cm: a 2.4 × 0.2 × 1.2 m wall whose corner broke off along a
/// 45° staircase (576 000 voxels, 36 600 of them under the staircase), written as one
/// fragment's grid. The baseline writes its voxels as a fog volume; the others its level set,
/// unsmoothed and with the fracture surface smoothed (output.fracture_smoothing_steps 4, the
/// default), which the frames of a cracking wall pay for its largest piece every frame unless
/// the piece's last surface is updated (BM_Frame_CrackingWallUpdated*).
constexpr int kWallLength = 240, kWallThickness = 20, kWallHeight = 120, kWallCorner = 60;

/// The wall's largest piece once its lower corner x + z < kWallCorner broke off and, with
/// `upperCornerToo`, also its upper corner x + z > 329 (8 700 voxels).
Body crackedWall(bool upperCornerToo = false)
{
    initialiseOpenVdb();
    LinkGrid::Ptr g = LinkGrid::create(0);
    g->tree().denseFill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(kWallLength - 1, kWallThickness - 1, kWallHeight - 1)), 0, true);
    linkAllNeighbours(*g);
    auto acc = g->getAccessor();
    for (int y = 0; y < kWallThickness; ++y) {
        for (int x = 0; x < kWallCorner; ++x) {  // every link across the lower staircase
            breakLink(acc, openvdb::Coord(x, y, kWallCorner - 1 - x), kPosX);
            breakLink(acc, openvdb::Coord(x, y, kWallCorner - 1 - x), kPosZ);
        }
        for (int s = 0; upperCornerToo && s < kWallCorner / 2; ++s) {  // the upper one, stepping down to +x
            const openvdb::Coord step(kWallLength - kWallCorner / 2 + s, y, kWallHeight - 1 - s);
            breakLink(acc, step, kPosX);
            breakLink(acc, step, kPosZ);
        }
    }
    std::vector<Body> parts = splitBody(makeBody(g, 0.01, 1900.0));
    std::sort(parts.begin(), parts.end(), [](const Body& a, const Body& b) { return a.mass.voxelCount > b.mass.voxelCount; });
    parts.front().id = 1;
    return parts.front();
}

OutputSettings frameSettings(FragmentGrids grids, int smoothingSteps)
{
    OutputSettings settings;
    settings.fragmentGrids = grids;
    settings.fractureSmoothingSteps = smoothingSteps;
    return settings;
}

void writeWallFrames(benchmark::State& state, FragmentGrids grids, int smoothingSteps)
{
    const std::vector<Body> wall = {crackedWall()};
    const std::string dir = (std::filesystem::temp_directory_path() / "spall-bench-frames").string();
    std::filesystem::create_directories(dir);
    int frame = 0;
    for (auto _ : state) {
        FrameWriter writer(dir, frameSettings(grids, smoothingSteps));  // a new writer: nothing kept from the last frame
        benchmark::DoNotOptimize(writer.write({frame++, 0.0}, wall));
    }
    std::filesystem::remove_all(dir);
    state.counters["voxels"] = double(wall.front().mass.voxelCount);
}
void BM_Frame_CrackedWallFog(benchmark::State& state) { writeWallFrames(state, FragmentGrids::Fog, 0); }
void BM_Frame_CrackedWallLevelSet(benchmark::State& state) { writeWallFrames(state, FragmentGrids::LevelSet, 0); }
void BM_Frame_CrackedWallSmoothed(benchmark::State& state) { writeWallFrames(state, FragmentGrids::LevelSet, 4); }
BENCHMARK(BM_Frame_CrackedWallFog)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Frame_CrackedWallLevelSet)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Frame_CrackedWallSmoothed)->Unit(benchmark::kMillisecond)->UseRealTime();

/// The same wall's frames as it cracks further, by one writer: each frame the piece loses its
/// upper corner or has it back, and the writer updates the last frame's surface
/// near that corner's crack instead of making it whole.
void writeCrackingWallFrames(benchmark::State& state, int smoothingSteps)
{
    const Body shapes[2] = {crackedWall(), crackedWall(true)};
    const std::string dir = (std::filesystem::temp_directory_path() / "spall-bench-frames-cracking").string();
    std::filesystem::create_directories(dir);
    FrameWriter writer(dir, frameSettings(FragmentGrids::LevelSet, smoothingSteps));
    int frame = 0;
    writer.write({frame++, 0.0}, {shapes[0]});
    for (auto _ : state) benchmark::DoNotOptimize(writer.write({frame, 0.0}, {shapes[frame % 2]})), ++frame;
    if (writer.surfacesUpdated() != frame - 1) state.SkipWithError("a frame made its surface whole");
    std::filesystem::remove_all(dir);
    state.counters["voxels"] = double(shapes[1].mass.voxelCount);
}
void BM_Frame_CrackingWallUpdated(benchmark::State& state) { writeCrackingWallFrames(state, 0); }
void BM_Frame_CrackingWallUpdatedSmoothed(benchmark::State& state) { writeCrackingWallFrames(state, 4); }
BENCHMARK(BM_Frame_CrackingWallUpdated)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Frame_CrackingWallUpdatedSmoothed)->Unit(benchmark::kMillisecond)->UseRealTime();

/// Console output plus, at the end, each benchmark's time relative to its baseline.
class RatioReporter : public benchmark::ConsoleReporter {
public:
    void ReportRuns(const std::vector<Run>& runs) override
    {
        for (const Run& r : runs)
            if (r.run_type == Run::RT_Iteration) {
                std::string name = r.benchmark_name();
                const std::string suffix = "/real_time";
                if (name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
                    name.resize(name.size() - suffix.size());
                mTimes[name] = r.GetAdjustedRealTime() * timeUnitSeconds(r.time_unit);
            }
        ConsoleReporter::ReportRuns(runs);
    }
    void Finalize() override
    {
        ConsoleReporter::Finalize();
        const std::pair<const char*, const char*> pairs[] = {
            {"BM_Label_Components256Whole", "BM_Label_TrivialPass256"},
            {"BM_Label_Components256Cut", "BM_Label_TrivialPass256"},
            {"BM_Loading_Links256", "BM_Label_TrivialPass256"},
            {"BM_Render_OpenVdbRayTracer", "BM_Render_Rasteriser"},
            {"BM_Pressure_Table/16", "BM_Pressure_DirectFits"},
            {"BM_Pressure_Table/64", "BM_Pressure_DirectFits"},
            {"BM_Pressure_Table/128", "BM_Pressure_DirectFits"},
            {"BM_Pressure_Table/512", "BM_Pressure_DirectFits"},
            {"BM_Pressure_Snapshot", "BM_Pressure_Table/128"},
            {"BM_Loads_BlastEngineering", "BM_Loads_PaperReflected"},
            {"BM_Loads_BlastEngineeringBehindABarrier", "BM_Loads_PaperReflected"},
            {"BM_Loads_WallBlastEngineering", "BM_Loads_WallPaperReflected"},
            {"BM_Voxelise_TorusWindingNumber", "BM_Voxelise_TorusLevelSet"},
            {"BM_Lattice_Step/24", "BM_Lattice_TrivialPass/24"},
            {"BM_Lattice_Step/60", "BM_Lattice_TrivialPass/60"},
            {"BM_Lattice_Step/100", "BM_Lattice_TrivialPass/100"},
            {"BM_Lattice_Step/60", "BM_Lattice_StepWithoutCrushing"},
            {"BM_Lattice_Step/24", "BM_Lattice_StepOneBondAtATime/24"},
            {"BM_Lattice_Step/60", "BM_Lattice_StepOneBondAtATime/60"},
            {"BM_Lattice_StepCracked/60", "BM_Lattice_StepCrackedOneBondAtATime/60"},
            {"BM_Lattice_Build", "BM_Lattice_Step/60"},
            {"BM_Integrate_FlightWithAirDrag", "BM_Integrate_Flight"},
            {"BM_Contacts_SlabOnGround", "BM_Contacts_BoundaryPass"},
            {"BM_Contacts_SlabOnSlab", "BM_Contacts_BoundaryPass"},
            {"BM_Frame_CrackedWallLevelSet", "BM_Frame_CrackedWallFog"},
            {"BM_Frame_CrackedWallSmoothed", "BM_Frame_CrackedWallFog"},
            {"BM_Frame_CrackingWallUpdated", "BM_Frame_CrackedWallLevelSet"},
            {"BM_Frame_CrackingWallUpdatedSmoothed", "BM_Frame_CrackedWallSmoothed"},
        };
        std::printf("\nRatios to the baseline in this run (time / baseline time):\n");
        for (auto [name, base] : pairs) {
            auto a = mTimes.find(name), b = mTimes.find(base);
            if (a == mTimes.end() || b == mTimes.end()) continue;
            // Pressure benchmarks differ in sample count: compare per evaluation.
            const double perEval = std::string(base) == "BM_Pressure_DirectFits" ? 64.0 : 1.0;
            std::printf("  %-32s / %-26s = %8.3f\n", name, base, a->second / b->second / perEval);
        }
    }

private:
    static double timeUnitSeconds(benchmark::TimeUnit unit)
    {
        switch (unit) {
        case benchmark::kNanosecond: return 1e-9;
        case benchmark::kMicrosecond: return 1e-6;
        case benchmark::kMillisecond: return 1e-3;
        case benchmark::kSecond: return 1.0;
        }
        return 1.0;
    }
    std::map<std::string, double> mTimes;
};

/// Error of the blast table against the direct fits, per resolution (docs/accuracy.md).
void printBlastTableAccuracy()
{
    std::printf("Blast table against the direct Kingery-Bulmash fits, 1 kg free air, 20000 distances in Z = 0.06..40:\n");
    std::printf("  %-18s %-22s %-22s %-22s\n", "nodes per decade", "Ps max / p99 rel err", "ta max / p99", "T+ max / p99");
    for (int nodes : {16, 32, 64, 128, 256, 512}) {
        BlastSettings bs;
        bs.tableNodesPerDecade = nodes;
        const BlastField field({Charge{Eigen::Vector3d::Zero(), 1.0, 0.0, BurstType::FreeAir}}, bs);
        std::vector<double> e[3];
        const int samples = 20000;
        for (int i = 0; i < samples; ++i) {
            const double z = 0.06 * std::pow(40.0 / 0.06, (i + 0.5) / samples);
            const BlastParameters d = blastParameters(BlastDataset::KingeryBulmash, BurstType::FreeAir, 1.0, z);
            const BlastParameters t = field.tableParameters(0, z);
            e[0].push_back(std::abs(t.peakOverpressurePa / d.peakOverpressurePa - 1));
            e[1].push_back(std::abs(t.arrivalTimeS / d.arrivalTimeS - 1));
            e[2].push_back(std::abs(t.positiveDurationS / d.positiveDurationS - 1));
        }
        std::printf("  %-18d", nodes);
        for (auto& v : e) {
            std::sort(v.begin(), v.end());
            std::printf(" %9.2e / %9.2e  ", v.back(), v[size_t(0.99 * (v.size() - 1))]);
        }
        std::printf("\n");
    }
    std::printf("\n");
}

}  // namespace

int main(int argc, char** argv)
{
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    printBlastTableAccuracy();
    RatioReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();
    return 0;
}
