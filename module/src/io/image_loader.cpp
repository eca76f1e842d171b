// Heightmaps and material layers read through OpenImageIO.
//
// Headers are checked (size against the cap, channel count, pixel type) before any pixel buffer
// is allocated, and integer pixels are read in their native type so that a 16-bit PNG gives
// 0..65535 rather than OIIO's normalised 0..1.
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <array>
#include <limits>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "format.h"
#include "io/geotiff.h"
#include "io/loader_common.h"
#include "io/png_check.h"
#include "io/tiff_tags.h"
#include "ridgeline/log.h"

namespace ridgeline::io {

namespace detail {

std::string heightmap_name(const std::string& path) {
  return "heightmap '" + path + "'";
}

Status check_regular_file(const std::string& path, const std::string& name) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  if (st.type() == std::filesystem::file_type::not_found) return Error{name + ": no such file"};
  if (ec) return Error{name + ": cannot access: " + ec.message()};
  if (st.type() == std::filesystem::file_type::directory) return Error{name + ": is a directory"};
  if (st.type() != std::filesystem::file_type::regular) return Error{name + ": not a regular file"};
  return {};
}

void warn(const std::string& name, const std::string& what, LoadReport* report) {
  log_message(LogLevel::kWarning, name + ": " + what);
  if (report != nullptr) report->warnings.push_back(what);
}

}  // namespace detail

namespace {

using OIIO::ImageInput;
using OIIO::ImageSpec;
using OIIO::TypeDesc;

// OIIO's error text holds one message per line, and a reader often reports one problem twice
// (libpng's read callback, then its error handler quoting it: "Read error: hit end of file" and
// "PNG read error: IDAT: Read error: hit end of file"). Keep each message once, on one line,
// dropping those that another one repeats.
std::string one_line(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(start, end - start);
    while (!line.empty() && (line.back() == ' ' || line.back() == '\r')) line.pop_back();
    if (!line.empty()) lines.push_back(std::move(line));
    start = end + 1;
  }
  std::string out;
  for (std::size_t k = 0; k < lines.size(); ++k) {
    bool repeated = false;
    for (std::size_t o = 0; o < lines.size() && !repeated; ++o)
      repeated =
          o != k && lines[o].find(lines[k]) != std::string::npos && (lines[o] != lines[k] || o < k);
    if (repeated) continue;
    if (!out.empty()) out += "; ";
    out += lines[k];
  }
  return out.empty() ? std::string("unknown error") : out;
}

std::string channel_list(const ImageSpec& spec) {
  std::string out;
  for (int c = 0; c < spec.nchannels; ++c) {
    if (c) out += ", ";
    out +=
        c < static_cast<int>(spec.channelnames.size()) ? spec.channelnames[c] : std::to_string(c);
  }
  return out;
}

// The image formats heightmaps and material layers are read from, by OpenImageIO's reader of that
// name. A file goes to the reader its extension names, or, when it has no such extension or that
// reader refuses it, to the one its first bytes name; no other reader ever sees it. OpenImageIO
// would otherwise offer a file to each of its ~28 readers in turn (video through ffmpeg, camera raw,
// DICOM, ...), and Debian's OpenImageIO 2.4 aborts the process in one of them (RLA, an assertion on
// a crafted channel type) on such a file. These are the readers the fuzz campaign runs
// (tests/fuzz/fuzz_image.cpp, docs/reliability/fuzzing.md).
struct ImageFormat {
  const char* reader;  // OpenImageIO's format name
  const char* label;
  std::array<const char*, 5> extensions;  // lower case, unused ones null
};
const ImageFormat kFormats[] = {
    {"png", "PNG", {"png"}},
    {"tiff", "TIFF", {"tif", "tiff"}},
    {"openexr", "OpenEXR", {"exr"}},
    {"pnm", "PNM", {"pgm", "ppm", "pbm", "pnm", "pfm"}},
    {"hdr", "Radiance HDR", {"hdr", "rgbe"}},
    {"bmp", "BMP", {"bmp", "dib"}},
    {"targa", "TGA", {"tga"}},
    {"jpeg", "JPEG", {"jpg", "jpeg", "jpe"}},
};
constexpr const char* kFormatList = "PNG, TIFF, OpenEXR, PNM, Radiance HDR, BMP, TGA or JPEG";

const ImageFormat* format_named(std::string_view reader) {
  for (const ImageFormat& f : kFormats)
    if (reader == f.reader) return &f;
  return nullptr;
}

const ImageFormat* format_by_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  if (ext.empty()) return nullptr;
  ext.erase(0, 1);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (const ImageFormat& f : kFormats)
    for (const char* e : f.extensions)
      if (e != nullptr && ext == e) return &f;
  return nullptr;
}

// The format whose signature the file starts with (TGA has none: by extension only).
const ImageFormat* format_by_signature(const std::string& path) {
  unsigned char h[8] = {};
  std::ifstream in(path, std::ios::binary);
  in.read(reinterpret_cast<char*>(h), sizeof h);
  const std::size_t n = static_cast<std::size_t>(in.gcount());
  auto starts = [&](std::initializer_list<unsigned char> sig) {
    return sig.size() <= n && std::equal(sig.begin(), sig.end(), h);
  };
  if (starts({0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a})) return format_named("png");
  if (starts({'I', 'I', '*', 0}) || starts({'M', 'M', 0, '*'}) || starts({'I', 'I', '+', 0}) ||
      starts({'M', 'M', 0, '+'}))
    return format_named("tiff");
  if (starts({0x76, 0x2f, 0x31, 0x01})) return format_named("openexr");
  if (n >= 2 && h[0] == 'P' && ((h[1] >= '1' && h[1] <= '6') || h[1] == 'f' || h[1] == 'F'))
    return format_named("pnm");
  if (starts({'#', '?'})) return format_named("hdr");
  if (starts({'B', 'M'})) return format_named("bmp");
  if (starts({0xff, 0xd8, 0xff})) return format_named("jpeg");
  return nullptr;
}

/// An open image whose header passed the checks common to heightmaps and material layers.
struct OpenImage {
  std::unique_ptr<ImageInput> input;
  std::uint32_t width = 0, height = 0;
  int nchannels = 0;
};

Result<OpenImage> open_image(const std::string& path, const std::string& name) {
  if (auto s = detail::check_regular_file(path, name); !s) return Error{s.message()};
  if (auto s = detail::check_png_chunks(path, name); !s) return Error{s.message()};
  const ImageFormat* by_extension = format_by_extension(path);
  const ImageFormat* by_signature = format_by_signature(path);
  if (by_extension == nullptr && by_signature == nullptr)
    return Error{fmt("%s: not a readable image: neither its name nor its first bytes are those of "
                     "a %s image (a headerless raw file needs --raw-size W,H)",
                     name.c_str(), kFormatList)};
  // Keep colour values as stored: OIIO would otherwise premultiply grey by alpha.
  ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  std::unique_ptr<ImageInput> in;
  std::string refusals;
  const ImageFormat* tries[] = {by_extension, by_signature != by_extension ? by_signature : nullptr};
  for (const ImageFormat* f : tries) {
    if (f == nullptr) continue;
    auto candidate = ImageInput::create(f->reader);
    if (!candidate) {
      refusals += fmt("%sno %s reader: %s", refusals.empty() ? "" : "; ", f->label,
                      one_line(OIIO::geterror()).c_str());
      continue;
    }
    ImageSpec opened;
    if (candidate->open(path, opened, config)) {
      in = std::move(candidate);
      break;
    }
    refusals += fmt("%sas %s: %s", refusals.empty() ? "" : "; ", f->label,
                    one_line(candidate->geterror()).c_str());
  }
  if (!in) return Error{name + ": not a readable image: " + refusals};
  const ImageSpec& spec = in->spec();
  if (spec.deep) return Error{name + ": deep images are not supported"};
  if (spec.depth > 1)
    return Error{fmt("%s: a volume image (%d slices); need a 2D image", name.c_str(), spec.depth)};
  if (spec.width < 0 || spec.height < 0 || spec.nchannels < 1)
    return Error{fmt("%s: invalid header (%d x %d pixels, %d channels)", name.c_str(), spec.width,
                     spec.height, spec.nchannels)};
  OpenImage out;
  out.width = static_cast<std::uint32_t>(spec.width);
  out.height = static_cast<std::uint32_t>(spec.height);
  out.nchannels = spec.nchannels;
  out.input = std::move(in);
  return out;
}

/// Reads channel `c` of the whole image as T (no normalisation: T is the native type or float
/// for float-like pixel types) into a buffer of width * height values.
template <class T>
Status read_channel(ImageInput& in, int c, TypeDesc type, std::vector<T>& out,
                    const std::string& name) {
  const ImageSpec& spec = in.spec();
  out.resize(static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.height));
  // A single channel in its stored type goes straight into `out`; anything else needs
  // OpenImageIO's conversion buffer, which it sizes for large images whatever the image's size
  // (tens of MB mapped and freed per read, most of the time a small load takes under ASan).
  const bool native =
      spec.nchannels == 1 && c == 0 && type == spec.format && spec.channelformats.empty();
  const bool ok = in.read_image(0, 0, c, c + 1, native ? TypeDesc::UNKNOWN : type, out.data());
  // Some readers report a problem (a short strip, a bad CRC) and still return true.
  if (!ok || in.has_error()) {
    out.clear();
    out.shrink_to_fit();
    return Error{
        name + ": cannot read the pixels (truncated or corrupt file?): " + one_line(in.geterror())};
  }
  return {};
}

template <class T>
Status read_as_float(ImageInput& in, int c, TypeDesc type, std::vector<float>& values,
                     const std::string& name) {
  std::vector<T> native;
  if (auto s = read_channel(in, c, type, native, name); !s) return s;
  values.resize(native.size());
  std::transform(native.begin(), native.end(), values.begin(),
                 [](T v) { return static_cast<float>(v); });
  return {};
}

/// Reads channel `c` as raw values: integers as the integer, floats as the float.
Status read_values(ImageInput& in, int c, std::vector<float>& values, const std::string& name) {
  const TypeDesc t = in.spec().channelformat(c);
  switch (t.basetype) {
    case TypeDesc::UINT8:
      return read_as_float<std::uint8_t>(in, c, TypeDesc::UINT8, values, name);
    case TypeDesc::INT8:
      return read_as_float<std::int8_t>(in, c, TypeDesc::INT8, values, name);
    case TypeDesc::UINT16:
      return read_as_float<std::uint16_t>(in, c, TypeDesc::UINT16, values, name);
    case TypeDesc::INT16:
      return read_as_float<std::int16_t>(in, c, TypeDesc::INT16, values, name);
    case TypeDesc::UINT32:
    case TypeDesc::INT32:
      // Up to 2^24 these are exact in float; larger ones are rounded (documented in io.h).
      if (t.basetype == TypeDesc::UINT32)
        return read_as_float<std::uint32_t>(in, c, TypeDesc::UINT32, values, name);
      return read_as_float<std::int32_t>(in, c, TypeDesc::INT32, values, name);
    case TypeDesc::HALF:
    case TypeDesc::FLOAT:
      return read_channel(in, c, TypeDesc::FLOAT, values, name);
    case TypeDesc::DOUBLE:
      // Values beyond float range become infinite and are refused by Heightfield::create.
      return read_as_float<double>(in, c, TypeDesc::DOUBLE, values, name);
    default:
      return Error{name + ": pixel type '" + std::string(t.c_str()) + "' is not supported"};
  }
}

/// The sample type's name as LoadReport gives it.
std::string pixel_type_name(TypeDesc t) {
  switch (t.basetype) {
    case TypeDesc::UINT8:
      return "uint8";
    case TypeDesc::INT8:
      return "int8";
    case TypeDesc::UINT16:
      return "uint16";
    case TypeDesc::INT16:
      return "int16";
    case TypeDesc::UINT32:
      return "uint32";
    case TypeDesc::INT32:
      return "int32";
    case TypeDesc::HALF:
      return "half";
    case TypeDesc::FLOAT:
      return "float";
    case TypeDesc::DOUBLE:
      return "double";
    default:
      return t.c_str();
  }
}

/// TIFF files from GDAL carry their no-data value in tag 42113 (GDAL_NODATA), which
/// OpenImageIO does not expose: read it (tiff_tags.h) and use it when the caller gave none.
void apply_file_nodata(const std::string& name, const std::vector<detail::TiffTag>& tags,
                       HeightfieldDesc& desc, LoadReport* report) {
  auto tag = detail::gdal_nodata_text(tags);
  if (!tag) {
    detail::warn(name, "GDAL_NODATA tag ignored: " + tag.error().message, report);
    return;
  }
  if (!*tag) return;
  const std::string& text = **tag;
  const auto v = detail::parse_nodata_text(text);
  if (!v) {
    detail::warn(name, "GDAL_NODATA tag '" + text + "' is not a number; ignored", report);
    return;
  }
  if (desc.nodata) {
    if (*desc.nodata != *v)
      log_message(LogLevel::kInfo,
                  fmt("%s: no-data value %s given; the file's GDAL_NODATA tag says '%s' (the "
                      "given value is used)",
                      name.c_str(), num(*desc.nodata).c_str(), text.c_str()));
    return;
  }
  if (!std::isfinite(*v)) {
    log_message(LogLevel::kInfo,
                fmt("%s: the file's GDAL_NODATA tag is '%s': non-finite samples are always "
                    "treated as missing",
                    name.c_str(), text.c_str()));
    return;
  }
  desc.nodata = *v;
  log_message(LogLevel::kInfo,
              fmt("%s: no-data value %s from the file's GDAL_NODATA tag (samples equal to it are "
                  "refused unless a fill policy is given)",
                  name.c_str(), num(*v).c_str()));
}

/// GeoTIFF placement (geotiff.h): spacing and origin from the file where the options allow it.
void apply_file_placement(const std::string& name, const std::vector<detail::TiffTag>& tags,
                          const LoadOptions& options, HeightfieldDesc& desc, LoadReport* report) {
  const detail::GeoTiffPlacement geo = detail::geotiff_placement(tags, desc.height);
  if (!geo.problem.empty()) {
    detail::warn(name,
                 "GeoTIFF placement ignored: " + geo.problem +
                     fmt("; spacing stays %.10g x %.10g m", desc.spacing_x, desc.spacing_z),
                 report);
    return;
  }
  if (!geo.placement) return;
  const FilePlacement& p = *geo.placement;
  if (report != nullptr) report->file_placement = p;
  const bool spacing = options.spacing_from_file;
  const bool origin = options.origin_from_file && p.has_origin;
  if (spacing) desc.spacing_x = p.spacing_x, desc.spacing_z = p.spacing_z;
  if (origin) desc.origin_x = p.origin_x, desc.origin_z = p.origin_z;
  if (report != nullptr) report->spacing_from_file = spacing, report->origin_from_file = origin;
  const std::string given_spacing = fmt("%.10g x %.10g m", desc.spacing_x, desc.spacing_z);
  const std::string given_origin = fmt("%.10g, %.10g", desc.origin_x, desc.origin_z);
  std::string what;
  if (spacing && origin)
    what = "spacing and origin taken from the file";
  else if (spacing && !p.has_origin)
    what = "spacing taken from the file; origin stays " + given_origin +
           " (degrees give no origin in metres)";
  else if (spacing)
    what = "spacing taken from the file; the given origin " + given_origin + " is used";
  else if (origin)
    what = "origin taken from the file; the given spacing " + given_spacing + " is used";
  else
    what = "not used: the given spacing " + given_spacing + " and origin " + given_origin +
           " are used";
  log_message(LogLevel::kInfo, name + ": " + p.description + "; " + what);
}

/// The tags the image loader reads from TIFF files: no-data and placement.
constexpr std::uint16_t kLoaderTags[] = {
    detail::kTagGdalNodata,          detail::kTagModelPixelScale, detail::kTagModelTiepoint,
    detail::kTagModelTransformation, detail::kTagGeoKeyDirectory, detail::kTagGeoDoubleParams};

/// Reads the TIFF tags OpenImageIO drops and applies them to `desc`.
Status apply_tiff_tags(const std::string& path, const std::string& name, ImageInput& in,
                       const LoadOptions& options, HeightfieldDesc& desc, LoadReport* report) {
  if (std::string(in.format_name()) != "tiff") return {};
  auto tags = detail::read_tiff_tags_file(path, kLoaderTags, detail::kMaxTagValues);
  if (!tags) {
    detail::warn(name, "TIFF tags (GDAL_NODATA, GeoTIFF) ignored: " + tags.error().message, report);
    return {};
  }
  if (!*tags) return {};
  apply_file_nodata(name, **tags, desc, report);
  apply_file_placement(name, **tags, options, desc, report);
  // The file's placement passes the same checks as the caller's (extent, finite origin).
  return validate_heightfield_desc(desc);
}

}  // namespace

namespace detail {

Result<std::vector<std::uint8_t>> load_material_ids(const LoadOptions& options, std::uint32_t width,
                                                    std::uint32_t height) {
  std::vector<std::uint8_t> ids;
  if (options.materials_path.empty()) return ids;
  const std::string name = "material image '" + options.materials_path + "'";
  auto img = open_image(options.materials_path, name);
  if (!img) return img.error();
  const ImageSpec& spec = img->input->spec();
  if (img->width != width || img->height != height)
    return Error{fmt("%s: %u x %u pixels; the heightmap has %u x %u samples", name.c_str(),
                     img->width, img->height, width, height)};
  if (img->nchannels != 1)
    return Error{fmt("%s: %d channels (%s); need one 8-bit channel of material ids", name.c_str(),
                     img->nchannels, channel_list(spec).c_str())};
  if (spec.channelformat(0).basetype != TypeDesc::UINT8)
    return Error{name + ": pixel type '" + std::string(spec.channelformat(0).c_str()) +
                 "'; need 8-bit unsigned material ids"};
  if (auto s = read_channel(*img->input, 0, TypeDesc::UINT8, ids, name); !s)
    return Error{s.message()};
  return ids;
}

Result<Heightfield> finish_heightfield(const HeightfieldDesc& desc, std::span<const float> values,
                                       const LoadOptions& options, LoadReport* report) {
  auto ids = load_material_ids(options, desc.width, desc.height);
  if (!ids) return ids.error();
  auto hf = Heightfield::create(desc, values, *ids);
  if (!hf) return hf;
  const double samples = double(hf->width()) * double(hf->height());
  const double fraction = double(hf->filled_samples()) / samples;
  if (fraction > kFilledWarningFraction)
    warn(desc.name,
         fmt("%llu of %.0f samples (%.1f %%) are filled from no-data by the %s fill policy: that "
             "part of the terrain is invented, not measured",
             static_cast<unsigned long long>(hf->filled_samples()), samples, 100.0 * fraction,
             desc.fill == FillPolicy::kNearest ? "nearest" : "constant"),
         report);
  return hf;
}

}  // namespace detail

Result<Heightfield> load_image(const std::string& path, const LoadOptions& options,
                               LoadReport* report) {
  const std::string name = detail::heightmap_name(path);
  auto img = open_image(path, name);
  if (!img) return img.error();
  const ImageSpec& spec = img->input->spec();

  HeightfieldDesc desc = options.placement;
  desc.width = img->width;
  desc.height = img->height;
  desc.name = name;
  // Size (and the cap), spacing, scale: all before a single pixel is allocated.
  if (auto s = validate_heightfield_desc(desc); !s) return Error{s.message()};

  int channel = 0;
  if (options.channel >= 0) {
    if (options.channel >= img->nchannels)
      return Error{fmt("%s: channel %d requested but the image has %d channel%s (%s)", name.c_str(),
                       options.channel, img->nchannels, img->nchannels == 1 ? "" : "s",
                       channel_list(spec).c_str())};
    channel = options.channel;
    if (img->nchannels > 1)
      log_message(LogLevel::kInfo, fmt("%s: using channel %d (%s) of %d", name.c_str(), channel,
                                       spec.channelnames[channel].c_str(), img->nchannels));
  } else if (img->nchannels == 2 && spec.alpha_channel == 1) {
    log_message(LogLevel::kInfo,
                fmt("%s: greyscale + alpha image; using the grey channel (0), %s", name.c_str(),
                    options.alpha_nodata ? "alpha 0 marking missing samples" : "ignoring alpha"));
  } else if (img->nchannels > 1) {
    return Error{
        fmt("%s: %d channels (%s); a heightmap needs one channel (choose one with the "
            "channel option, e.g. --channel 0)",
            name.c_str(), img->nchannels, channel_list(spec).c_str())};
  }

  if (report != nullptr) report->pixel_type = pixel_type_name(spec.channelformat(channel));
  if (auto s = apply_tiff_tags(path, name, *img->input, options, desc, report); !s)
    return Error{s.message()};

  std::vector<float> values;
  if (auto s = read_values(*img->input, channel, values, name); !s) return Error{s.message()};
  if (options.alpha_nodata) {
    const int alpha = spec.alpha_channel;
    if (alpha < 0 || alpha == channel)
      return Error{fmt("%s: alpha marks missing samples, but the image has no alpha channel "
                       "besides the heights (%s)",
                       name.c_str(), channel_list(spec).c_str())};
    std::vector<float> a;
    if (auto s = read_channel(*img->input, alpha, TypeDesc::FLOAT, a, name); !s)
      return Error{s.message()};
    // Non-finite samples are always missing (heightfield.h): the fill policy takes them.
    for (std::size_t k = 0; k < values.size(); ++k)
      if (a[k] == 0.0f) values[k] = std::numeric_limits<float>::quiet_NaN();
  }
  img->input->close();
  return detail::finish_heightfield(desc, values, options, report);
}

Result<Heightfield> load_heightmap(const std::string& path, const LoadOptions& options,
                                   const RawFormat* raw, LoadReport* report) {
  if (raw && raw->width != 0 && raw->height != 0) return load_raw(path, *raw, options, report);
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  if (ext == ".raw" || ext == ".r16" || ext == ".r32")
    return Error{detail::heightmap_name(path) +
                 ": a headerless raw file needs its size and sample type (--raw-size W,H "
                 "--raw-type u16|f32)"};
  return load_image(path, options, report);
}

}  // namespace ridgeline::io
