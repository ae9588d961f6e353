// Settings of the load stage: how the blast pressure becomes forces on faces.
#pragma once

#include <spall/core/Fields.h>

namespace spall {

struct LoadSettings {
    /// Faces hit head-on see the reflected pressure (Rankine–Hugoniot, blended by cos^2 of the
    /// angle of incidence) instead of the paper's side-on pressure: a face that stops the flow
    /// feels the reflected wave, 2 to 8 times the side-on one (docs/architecture.md).
    bool reflectedPressure = true;
};

// Keys and ranges (src/loads/Settings.cpp).
template <>
const std::vector<Field<LoadSettings>>& fieldTable<LoadSettings>();

}  // namespace spall
