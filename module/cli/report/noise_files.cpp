// The noise field and circle path as files (noise_files.h).
#include "report/noise_files.h"

#include <OpenImageIO/imageio.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "cli_util.h"
#include "ridgeline/scenes.h"

namespace ridgeline::report {

Status write_noise_field(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return Error{"cannot create directory '" + dir + "': " + ec.message()};
  const auto png = (std::filesystem::path(dir) / "noise1025.png").string();
  const auto tmp = png + ".tmp.png";
  const std::vector<std::uint16_t> v = scenes::noise_samples();
  {
    auto out = OIIO::ImageOutput::create(tmp);
    if (!out) return Error{"cannot write '" + png + "': no PNG writer"};
    const OIIO::ImageSpec spec(int(scenes::kNoiseSize), int(scenes::kNoiseSize), 1,
                               OIIO::TypeDesc::UINT16);
    if (!out->open(tmp, spec) || !out->write_image(OIIO::TypeDesc::UINT16, v.data()) ||
        !out->close())
      return Error{"cannot write '" + png + "': " + out->geterror()};
  }
  std::filesystem::rename(tmp, png, ec);
  if (ec) return Error{"cannot write '" + png + "': " + ec.message()};
  nlohmann::ordered_json frames = nlohmann::ordered_json::array();
  for (const Camera& c : scenes::noise_circle())
    frames.push_back({{"eye", {c.eye.x, c.eye.y, c.eye.z}},
                      {"target", {c.target.x, c.target.y, c.target.z}},
                      {"fov_y", int(c.fov_y_deg)},
                      {"viewport", {c.viewport.x, c.viewport.y}}});
  const nlohmann::ordered_json path = {{"version", 1}, {"frames", frames}};
  const auto json = (std::filesystem::path(dir) / "noise1025_circle.json").string();
  return cli::write_output(path.dump() + "\n", json);
}

}  // namespace ridgeline::report
