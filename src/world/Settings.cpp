#include <spall/world/StaticWorld.h>

namespace spall {

template <>
const std::vector<Field<GroundPlane>>& fieldTable<GroundPlane>()
{
    static const std::vector<Field<GroundPlane>> table = {
        {"ground.enabled", &GroundPlane::enabled},
        {"ground.normal", &GroundPlane::normal, {}, 1.0, VectorCheck::NonZero},
        {"ground.height_m", &GroundPlane::offsetM, closed(-1e6, 1e6)},
        {"ground.restitution", &GroundPlane::restitution, closed(0, kMaxRestitution)},
        {"ground.friction", &GroundPlane::friction, closed(0, kMaxFriction)},
        {"ground.youngs_modulus_pa", &GroundPlane::youngsModulusPa, closed(0, 1e13)},
        {"ground.poissons_ratio", &GroundPlane::poissonsRatio, closed(0, 0.49)},
        {"ground.density_kg_m3", &GroundPlane::densityKgM3, closed(100, 30000)},
    };
    return table;
}

template <>
const std::vector<Field<StaticBox>>& fieldTable<StaticBox>()
{
    static const std::vector<Field<StaticBox>> table = {
        {"position_m", &StaticBox::centreM},
        {"size_m", &StaticBox::halfExtentM, {}, 2.0, VectorCheck::Positive},
        {"rotation_deg", &StaticBox::rotationDeg},
        {"restitution", &StaticBox::restitution, closed(0, kMaxRestitution)},
        {"friction", &StaticBox::friction, closed(0, kMaxFriction)},
        {"holds", choice(&StaticBox::holds)},
        {"bearing_pressure_pa", &StaticBox::bearingPressurePa, closed(0, 1e9)},
    };
    return table;
}

}  // namespace spall
