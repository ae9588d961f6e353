// Settings of the load stage: how the blast pressure becomes forces on faces.
#pragma once

#include <spall/core/EnumNames.h>
#include <spall/core/Fields.h>

namespace spall {

/// Which rule turns the free field into face loads.
enum class LoadModel {
    /// Blast engineering's procedure (UFC 3-340-02 ch. 2, loads/FacePulse.h): reflected pulse
    /// with clearing on faces that look at a charge, side-on plus drag on the others, the
    /// negative phase on every face, force along the face normal, integrated over each step.
    BlastEngineering,
    /// The paper's rule (section 4.1): side-on p A cos(theta) along the radius on faces that
    /// look at a charge, sampled at the start of each step.
    Paper,
    /// The paper's rule with an ideal-gas reflection of the instantaneous pressure, blended by
    /// cos^2 of the angle of incidence (spall's rule before blast engineering's).
    PaperReflected,
};
template <>
struct EnumNames<LoadModel> {
    static constexpr std::pair<LoadModel, const char*> kNames[] = {
        {LoadModel::BlastEngineering, "blast-engineering"}, {LoadModel::Paper, "paper"}, {LoadModel::PaperReflected, "paper-reflected"}};
};

struct LoadSettings {
    LoadModel model = LoadModel::BlastEngineering;
};

// Keys and ranges (src/loads/Settings.cpp).
template <>
const std::vector<Field<LoadSettings>>& fieldTable<LoadSettings>();

}  // namespace spall
