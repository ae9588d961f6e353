#include <spall/dynamics/AirDrag.h>

#include <algorithm>
#include <cmath>

namespace spall {

Air airOf(const Atmosphere& atmosphere)
{
    constexpr double kDryAirGasConstant = 287.05;                 // J/(kg K)
    constexpr double kSutherlandViscosityPaS = 1.716e-5;          // at 273.15 K
    constexpr double kSutherlandReferenceK = 273.15, kSutherlandConstantK = 110.4;
    const double t = atmosphere.temperatureK;
    Air air;
    air.densityKgM3 = atmosphere.pressurePa / (kDryAirGasConstant * t);
    air.viscosityPaS = kSutherlandViscosityPaS * std::pow(t / kSutherlandReferenceK, 1.5) * (kSutherlandReferenceK + kSutherlandConstantK) /
                       (t + kSutherlandConstantK);
    return air;
}

double haiderLevenspielDragCoefficient(double reynolds, double sphericity)
{
    // Haider & Levenspiel (1989) eq. 10 with its coefficients eq. 11 (also ANSYS Fluent theory
    // guide, eq. 15.3-2/3).
    const double phi = sphericity, phi2 = phi * phi, phi3 = phi2 * phi;
    const double a = std::exp(2.3288 - 6.4581 * phi + 2.4486 * phi2);
    const double b = 0.0964 + 0.5565 * phi;
    const double c = std::exp(4.905 - 13.8944 * phi + 18.4222 * phi2 - 10.2599 * phi3);
    const double d = std::exp(1.4681 + 12.2584 * phi - 20.7322 * phi2 + 15.8855 * phi3);
    const double re = std::min(reynolds, kHaiderLevenspielMaxReynolds);
    return 24.0 / re * (1.0 + a * std::pow(re, b)) + c * re / (d + re);
}

DragShape dragShapeOf(const Body& body)
{
    const double h = body.voxelSizeM;
    const double volumeM3 = static_cast<double>(body.mass.voxelCount) * h * h * h;
    const double surfaceM2 = static_cast<double>(body.exposedFaces.size()) * h * h;
    DragShape shape;
    shape.equivalentDiameterM = std::cbrt(6.0 * volumeM3 / M_PI);
    if (surfaceM2 > 0.0) shape.sphericity = std::min(1.0, M_PI * shape.equivalentDiameterM * shape.equivalentDiameterM / surfaceM2);
    return shape;
}

Eigen::Vector3d airDragForceN(const DragShape& shape, const Air& air, const Eigen::Vector3d& velocityMS)
{
    const double speed = velocityMS.norm();
    if (speed <= 0.0 || shape.equivalentDiameterM <= 0.0) return Eigen::Vector3d::Zero();
    const double d = shape.equivalentDiameterM;
    const double reynolds = air.densityKgM3 * speed * d / air.viscosityPaS;
    const double areaM2 = 0.25 * M_PI * d * d;
    return -0.5 * air.densityKgM3 * haiderLevenspielDragCoefficient(reynolds, shape.sphericity) * areaM2 * speed * velocityMS;
}

}  // namespace spall
