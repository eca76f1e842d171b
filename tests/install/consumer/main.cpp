// An outside project using the installed Ridgeline::terrain: builds a terrain and queries it.
#include <ridgeline/heightfield.h>
#include <ridgeline/terrain.h>

#include <cmath>
#include <cstdio>
#include <vector>

int main() {
  ridgeline::HeightfieldDesc desc;
  desc.width = 3;
  desc.height = 3;
  std::vector<float> values(9, 2.0f);
  auto hf = ridgeline::Heightfield::create(desc, values);
  if (!hf) {
    std::fprintf(stderr, "%s\n", hf.error().message.c_str());
    return 1;
  }
  auto terrain = ridgeline::Terrain::create(std::move(hf).value()).value();
  auto h = terrain->height(1.5, 0.5);
  if (!h || std::abs(*h - 2.0) > 1e-9) return 1;
  std::printf("consumer: height %.3f\n", *h);
  return 0;
}
