// Material table. Friction factors are relative to grass (the tuning surface); they follow the
// usual ordering of tyre grip on dry rock > grass > gravel > sand > mud > snow.
#include "materials.h"

namespace game {
namespace {

constexpr Material kMaterials[kMaterialCount] = {
    {"grass", {0.28f, 0.48f, 0.18f}, 1.00}, {"rock", {0.47f, 0.44f, 0.42f}, 1.05},
    {"sand", {0.76f, 0.70f, 0.50f}, 0.70},  {"snow", {0.93f, 0.94f, 0.97f}, 0.40},
    {"mud", {0.36f, 0.27f, 0.18f}, 0.55},   {"gravel", {0.58f, 0.55f, 0.50f}, 0.85}};
constexpr Material kUnknown = {"unknown", {0.5f, 0.5f, 0.5f}, 1.0};

}  // namespace

const Material& material(std::uint8_t id) noexcept {
  return id < kMaterialCount ? kMaterials[id] : kUnknown;
}

}  // namespace game
