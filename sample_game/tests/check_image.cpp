// game_image_check SHOT.png [REFERENCE.png]: pixel statistics of a game screenshot, printed as
// JSON; exit 1 when a check fails:
//  - not blank: the luminance varies (standard deviation > 12 of 255);
//  - terrain shading: the lower half (terrain under the follow camera) has a luminance spread
//    (standard deviation > 4) and at least 40 distinct colours (quantised to 5 bits);
//  - a vehicle: at least 60 pixels of the truck's orange paint (no terrain or sky colour is
//    that hue: r > 120, r > 1.6 g, g > 1.5 b);
//  - with a reference: the same size, mean absolute difference <= 4 of 255 per channel and at
//    most 2 % of pixels differing by more than 48 in any channel (llvmpipe is deterministic for
//    a fixed threshold and time step; the tolerance absorbs rasteriser differences between Mesa
//    builds).
#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>
#include <vector>

#include "io/oiio_lsan_suppressions.h"

namespace {

bool load(const std::string& path, int& w, int& h, std::vector<unsigned char>& rgb) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    std::fprintf(stderr, "cannot open '%s': %s\n", path.c_str(), OIIO::geterror().c_str());
    return false;
  }
  const OIIO::ImageSpec& s = in->spec();
  w = s.width;
  h = s.height;
  if (s.nchannels < 3) {
    std::fprintf(stderr, "'%s': %d channels, need RGB\n", path.c_str(), s.nchannels);
    return false;
  }
  std::vector<unsigned char> all(std::size_t(w) * h * s.nchannels);
  if (!in->read_image(0, 0, 0, s.nchannels, OIIO::TypeDesc::UINT8, all.data())) {
    std::fprintf(stderr, "'%s': %s\n", path.c_str(), in->geterror().c_str());
    return false;
  }
  rgb.resize(std::size_t(w) * h * 3);
  for (std::size_t i = 0; i < std::size_t(w) * h; ++i)
    for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = all[i * s.nchannels + c];
  return true;
}

double luminance(const unsigned char* p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }

double stddev(const std::vector<double>& v) {
  double m = 0, q = 0;
  for (double x : v) m += x;
  m /= double(v.size());
  for (double x : v) q += (x - m) * (x - m);
  return std::sqrt(q / double(v.size()));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: game_image_check SHOT.png [REFERENCE.png]\n");
    return 2;
  }
  int w = 0, h = 0;
  std::vector<unsigned char> img;
  if (!load(argv[1], w, h, img)) return 1;
  std::vector<double> lum, lower;
  std::set<int> colours;
  long orange = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const unsigned char* p = &img[(std::size_t(y) * w + x) * 3];
      const double l = luminance(p);
      lum.push_back(l);
      if (y >= h / 2) {
        lower.push_back(l);
        colours.insert((p[0] >> 3) << 10 | (p[1] >> 3) << 5 | (p[2] >> 3));
      }
      if (p[0] > 120 && p[0] > 1.6 * p[1] && p[1] > 1.5 * p[2]) ++orange;
    }
  const double sd = stddev(lum), sd_lower = stddev(lower);
  bool ok = true;
  auto check = [&ok](bool c, const char* what) {
    if (!c) {
      std::fprintf(stderr, "FAILED: %s\n", what);
      ok = false;
    }
  };
  check(sd > 12, "the picture is blank (luminance does not vary)");
  check(sd_lower > 4 && colours.size() >= 40, "no terrain shading in the lower half");
  check(orange >= 60, "no vehicle (too few pixels of the truck's orange paint)");
  double mad = -1, big = -1;
  if (argc == 3) {
    int rw = 0, rh = 0;
    std::vector<unsigned char> ref;
    if (!load(argv[2], rw, rh, ref)) return 1;
    if (rw != w || rh != h) {
      std::fprintf(stderr, "FAILED: size %d x %d, reference %d x %d\n", w, h, rw, rh);
      return 1;
    }
    double sum = 0;
    long n_big = 0;
    for (std::size_t i = 0; i < std::size_t(w) * h; ++i) {
      int worst = 0;
      for (int c = 0; c < 3; ++c) {
        const int d = std::abs(int(img[i * 3 + c]) - int(ref[i * 3 + c]));
        sum += d;
        worst = std::max(worst, d);
      }
      n_big += worst > 48;
    }
    mad = sum / (double(w) * h * 3);
    big = double(n_big) / (double(w) * h);
    check(mad <= 4.0, "mean absolute difference from the reference above 4");
    check(big <= 0.02, "more than 2 % of pixels differ from the reference by more than 48");
  }
  std::printf("{\"width\": %d, \"height\": %d, \"luminance_sd\": %.2f, \"lower_half_sd\": %.2f, "
              "\"lower_half_colours\": %zu, \"orange_pixels\": %ld, \"reference_mad\": %.3f, "
              "\"reference_big_diff_fraction\": %.4f, \"ok\": %s}\n",
              w, h, sd, sd_lower, colours.size(), orange, mad, big, ok ? "true" : "false");
  return ok ? 0 : 1;
}
