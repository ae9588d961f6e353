#include <spall/output/RunCharges.h>

#include <spall/core/Error.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace spall {

std::vector<Charge> chargesOfRun(const std::string& outDir)
{
    const std::filesystem::path path = std::filesystem::path(outDir) / "scene.json";
    std::vector<Charge> charges;
    std::ifstream in(path);
    if (!in) return charges;
    try {
        const nlohmann::json scene = nlohmann::json::parse(in);
        for (const auto& entry : scene.value("charges", nlohmann::json::array())) {
            const auto& p = entry.at("position_m");
            Charge charge;
            charge.positionM = {p.at(0).get<double>(), p.at(1).get<double>(), p.at(2).get<double>()};
            charge.tntKg = entry.at("tnt_kg").get<double>();
            charges.push_back(charge);
        }
    } catch (const std::exception& e) {
        throw IoError(path.string() + ": charges[].position_m or tnt_kg cannot be read: " + e.what());
    }
    return charges;
}

}  // namespace spall
