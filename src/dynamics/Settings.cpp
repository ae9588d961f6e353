#include <spall/dynamics/Settings.h>

namespace spall {

template <>
const std::vector<Field<WorldSettings>>& fieldTable<WorldSettings>()
{
    // The ground and the colliders have tables of their own.
    static const std::vector<Field<WorldSettings>> table = {
        {"gravity_m_s2", &WorldSettings::gravityMS2},
        {"solver.air_drag", choice(&WorldSettings::airDrag)},
        {"solver.linear_drag_per_s", &WorldSettings::linearDragPerS, closed(0, 1e6)},
        {"solver.angular_drag_per_s", &WorldSettings::angularDragPerS, closed(0, 1e6)},
    };
    return table;
}

template <>
const std::vector<Field<SleepSettings>>& fieldTable<SleepSettings>()
{
    static const std::vector<Field<SleepSettings>> table = {
        {"solver.sleep", &SleepSettings::enabled},
        {"solver.sleep_speed_m_s", &SleepSettings::speedMS, closed(0, 1e3)},
        {"solver.sleep_time_s", &SleepSettings::timeS, closed(0, 1e5)},
    };
    return table;
}

template <>
const std::vector<Field<TimeStepSettings>>& fieldTable<TimeStepSettings>()
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

template <>
const std::vector<Field<CollisionSettings>>& fieldTable<CollisionSettings>()
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
