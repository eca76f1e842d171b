// `ridge query`: heights and face normals at points read from CSV.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "cli_util.h"
#include "commands.h"
#include "terrain_args.h"

namespace ridgeline::cli {

namespace {

struct QueryOptions {
  TerrainArgs terrain;
  std::string points_path;
};

struct Point {
  double x, z;
};

std::string fmt_fields(const std::string& where, std::size_t n, const std::string& line) {
  return where + ": " + std::to_string(n) + " field" + (n == 1 ? "" : "s") + " in '" + line +
         "'; expected x,z";
}

/// Reads every point first, so a bad line fails the command before any output is written.
Result<std::vector<Point>> read_points(std::istream& in, const std::string& name) {
  std::vector<Point> points;
  std::string line;
  std::size_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;  // blank lines are skipped
    const std::string where = name + " line " + std::to_string(number);
    std::vector<std::string_view> fields;
    std::string_view rest = line;
    for (std::size_t comma; (comma = rest.find(',')) != std::string_view::npos;) {
      fields.push_back(rest.substr(0, comma));
      rest.remove_prefix(comma + 1);
    }
    fields.push_back(rest);
    if (fields.size() != 2) return Error{fmt_fields(where, fields.size(), line)};
    auto x = parse_finite(fields[0], "x");
    if (!x) return Error{where + ": " + x.error().message + " in '" + line + "'; expected x,z"};
    auto z = parse_finite(fields[1], "z");
    if (!z) return Error{where + ": " + z.error().message + " in '" + line + "'; expected x,z"};
    points.push_back({*x, *z});
  }
  if (in.bad()) return Error{name + ": read error"};
  return points;
}

int run_query(const QueryOptions& o) {
  Result<std::vector<Point>> points = std::vector<Point>{};
  if (o.points_path == "-") {
    points = read_points(std::cin, "standard input");
  } else {
    std::ifstream in(o.points_path);
    if (!in)
      return report_error("points file '" + o.points_path +
                          "': cannot open: " + std::strerror(errno));
    points = read_points(in, "points file '" + o.points_path + "'");
  }
  if (!points) return report_error(points.error().message);
  auto terrain = o.terrain.load_terrain();
  if (!terrain) return report_error(terrain.error().message);
  const Terrain& t = **terrain;
  std::string out;
  for (const Point& p : *points) {
    out += csv_number(p.x);
    out += ',';
    out += csv_number(p.z);
    const auto h = t.height(p.x, p.z);
    const auto n = t.face_normal(p.x, p.z);
    if (h && n) {
      for (double v : {*h, double(n->x), double(n->y), double(n->z)}) {
        out += ',';
        out += csv_number(v);
      }
    } else {
      out += ",,,,";  // off the terrain: empty fields
    }
    out += '\n';
    if (out.size() > (1 << 16)) {
      std::fwrite(out.data(), 1, out.size(), stdout);
      out.clear();
    }
  }
  std::fwrite(out.data(), 1, out.size(), stdout);
  if (std::fflush(stdout) != 0 || std::ferror(stdout))
    return report_error("cannot write to standard output");
  return 0;
}

}  // namespace

Command add_query_command(CLI::App& parent) {
  auto* app = parent.add_subcommand(
      "query",
      "Height and face normal at points: reads lines 'x,z', writes lines 'x,z,height,nx,ny,nz' "
      "(17 significant digits; empty fields off the terrain; no header)");
  auto o = std::make_shared<QueryOptions>();
  o->terrain.add_to(*app);
  app->add_option("--points", o->points_path, "CSV file of 'x,z' lines in metres ('-': stdin)")
      ->type_name("IN.csv")
      ->required();
  return {app, [o] { return run_query(*o); }};
}

}  // namespace ridgeline::cli
