// An outside project using the installed Ridgeline::io and Ridgeline::lua: writes a raw
// heightmap, loads it through Ridgeline::io, and runs a sandboxed script against the terrain
// through Ridgeline::lua's Host.
#include <ridgeline/io.h>
#include <ridgeline/lua/host.h>
#include <ridgeline/terrain.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

int main(int argc, char** argv) {
  if (argc < 2) return 2;
  const std::string path = argv[1];
  {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return 1;
    const std::vector<std::uint16_t> v(17 * 17, 1000);
    std::fwrite(v.data(), sizeof(std::uint16_t), v.size(), f);
    std::fclose(f);
  }
  ridgeline::io::LoadOptions options;
  options.placement.spacing_x = options.placement.spacing_z = 2.0;
  options.placement.height_scale = 0.01;
  const ridgeline::io::RawFormat raw{17, 17, ridgeline::io::RawType::kU16};
  auto hf = ridgeline::io::load_heightmap(path, options, &raw);
  if (!hf) {
    std::fprintf(stderr, "%s\n", hf.error().message.c_str());
    return 1;
  }
  auto terrain = ridgeline::Terrain::create(std::move(hf).value()).value();
  auto h = terrain->height(5.0, 7.0);
  if (!h || std::abs(*h - 10.0) > 1e-6) return 1;
  auto host = ridgeline::lua::Host::create();
  if (!host) {
    std::fprintf(stderr, "%s\n", host.error().message.c_str());
    return 1;
  }
  auto st = (*host)->run(
      "local t = ridgeline.default_terrain(); assert(type(t:height(10, 10)) == 'number')",
      "consumer");
  if (!st) {
    std::fprintf(stderr, "%s\n", st.message().c_str());
    return 1;
  }
  std::printf("consumer (io, lua): height %.3f, script ran\n", *h);
  return 0;
}
