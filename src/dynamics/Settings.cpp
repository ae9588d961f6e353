#include <spall/dynamics/Settings.h>

namespace spall {

namespace {

constexpr double kMaxRestitution = 1.0;
constexpr double kMaxFriction = 100.0;

}  // namespace

const std::vector<Field<GroundPlane>>& FieldTable<GroundPlane>::fields()
{
    static const std::vector<Field<GroundPlane>> table = {
        {"ground.enabled", &GroundPlane::enabled},
        {"ground.normal", &GroundPlane::normal, {}, 1.0, VectorCheck::NonZero},
        {"ground.height_m", &GroundPlane::offsetM, closed(-1e6, 1e6)},
        {"ground.restitution", &GroundPlane::restitution, closed(0, kMaxRestitution)},
        {"ground.friction", &GroundPlane::friction, closed(0, kMaxFriction)},
    };
    return table;
}

const std::vector<Field<StaticBox>>& FieldTable<StaticBox>::fields()
{
    static const std::vector<Field<StaticBox>> table = {
        {"position_m", &StaticBox::centreM},
        {"size_m", &StaticBox::halfExtentM, {}, 2.0, VectorCheck::Positive},
        {"rotation_deg", &StaticBox::rotationDeg},
        {"restitution", &StaticBox::restitution, closed(0, kMaxRestitution)},
        {"friction", &StaticBox::friction, closed(0, kMaxFriction)},
    };
    return table;
}

const std::vector<Field<WorldSettings>>& FieldTable<WorldSettings>::fields()
{
    // The ground and the colliders have tables of their own.
    static const std::vector<Field<WorldSettings>> table = {
        {"gravity_m_s2", &WorldSettings::gravityMS2},
        {"solver.linear_drag_per_s", &WorldSettings::linearDragPerS, closed(0, 1e6)},
        {"solver.angular_drag_per_s", &WorldSettings::angularDragPerS, closed(0, 1e6)},
    };
    return table;
}

const std::vector<Field<SleepSettings>>& FieldTable<SleepSettings>::fields()
{
    static const std::vector<Field<SleepSettings>> table = {
        {"solver.sleep", &SleepSettings::enabled},
        {"solver.sleep_speed_m_s", &SleepSettings::speedMS, closed(0, 1e3)},
        {"solver.sleep_time_s", &SleepSettings::timeS, closed(0, 1e5)},
    };
    return table;
}

const std::vector<Field<TimeStepSettings>>& FieldTable<TimeStepSettings>::fields()
{
    // min_time_step_s must also not exceed max_time_step_s (checked where both are known).
    static const std::vector<Field<TimeStepSettings>> table = {
        {"solver.integrator", choice(&TimeStepSettings::integrator)},
        {"solver.max_time_step_s", &TimeStepSettings::maxTimeStepS, aboveZeroUpTo(10)},
        {"solver.min_time_step_s", &TimeStepSettings::minTimeStepS, aboveZeroUpTo(10)},
        {"solver.front_fraction_voxels", &TimeStepSettings::frontFraction, aboveZeroUpTo(100)},
        {"solver.pulse_fraction", &TimeStepSettings::pulseFraction, aboveZeroUpTo(1)},
        {"solver.speed_fraction_voxels", &TimeStepSettings::speedFraction, aboveZeroUpTo(100)},
    };
    return table;
}

const std::vector<Field<CollisionSettings>>& FieldTable<CollisionSettings>::fields()
{
    static const std::vector<Field<CollisionSettings>> table = {
        {"collisions.method", choice(&CollisionSettings::method)},
        {"collisions.restitution", &CollisionSettings::restitution, closed(0, kMaxRestitution)},
        {"collisions.friction", &CollisionSettings::friction, closed(0, kMaxFriction)},
        {"collisions.solver_iterations", &CollisionSettings::solverIterations, closed(1, 1000)},
        {"collisions.penetration_tolerance_voxels", &CollisionSettings::penetrationToleranceVoxels, aboveZeroUpTo(1)},
    };
    return table;
}

}  // namespace spall
