// The frame loop (frame_loop.h). What is timed is the technique's update (and its output step)
// alone; everything the loop measures runs between frames on the measured frames only, the same
// for every technique, so that no technique's next update finds the caches as another
// technique's diagnostics left them.
#include "ridgeline/bench/frame_loop.h"

#include <algorithm>
#include <cmath>

#include "ridgeline/bench/clock.h"

namespace ridgeline::bench {

const std::vector<double>& Run::named(const std::string& name) const {
  static const std::vector<double> kEmpty;
  const auto it = series.find(name);
  return it == series.end() ? kEmpty : it->second;
}

namespace {

// The numbers of `fields` appended to the run's named series; the fields merged into `frame`.
void keep_fields(const Json& fields, Run& r, Json* frame) {
  for (const auto& [key, value] : fields.items()) {
    if (value.is_number() && !value.is_boolean()) r.series[key].push_back(value.get<double>());
    if (frame != nullptr) (*frame)[key] = value;
  }
}

void push_if(std::vector<double>& v, double x) {
  if (!std::isnan(x)) v.push_back(x);
}

// Per technique: its run and the mesh of frame nK - 1 (for the jump and the pop).
struct Lane {
  Technique* t;
  Run run;
  Drawable before;
  DrawnHeights now, now_m, prev, prev_m;
};

}  // namespace

Result<std::vector<Run>> run_path(const std::vector<Technique*>& techniques,
                                  const std::vector<Camera>& path, const MeshErrorMeter* meter,
                                  const LoopOptions& o) {
  if (path.empty()) return Error{"frame loop: the camera path has no frames"};
  const auto t_run = Clock::now();
  const std::uint32_t K = o.error_every == 0 ? 0 : o.pops ? std::max(o.error_every, 2u)
                                                          : o.error_every;
  if (K > 0 && meter == nullptr) return Error{"frame loop: measuring needs a meter"};
  auto measured = [&](std::size_t k) {
    return K > 0 && k % K == 0 && (!o.pops || k > 0);
  };
  auto captured_before = [&](std::size_t k) { return o.pops && K > 0 && k % K == K - 1; };

  std::vector<Lane> lanes;
  for (Technique* t : techniques) {
    lanes.push_back({t, {}, {}, {}, {}, {}, {}});
    lanes.back().run.technique = t->name();
    lanes.back().run.has_morph = t->geomorphs();
    if (auto s = t->start(path.front()); !s) return Error{s.message()};
  }
  OtherWork other(o.flush_mb);

  for (std::uint64_t k = 0; k < o.warmup; ++k)
    for (Lane& l : lanes) {
      l.t->before_update();
      other.touch();
      if (!l.t->idle())
        if (auto s = l.t->update(path[k % path.size()]); !s) return Error{s.message()};
      if (l.t->has_output()) l.t->output();
    }

  for (std::uint64_t rep = 0; rep < std::max<std::uint64_t>(o.repeat, 1); ++rep) {
    for (std::size_t k = 0; k < path.size(); ++k) {
      const Camera& c = path[k];
      if (o.before_frame)
        if (auto s = o.before_frame(k); !s) return Error{s.message()};
      if (o.only_measured_frames && !measured(k) && !captured_before(k)) continue;
      for (std::size_t n = 0; n < lanes.size(); ++n) {
        Lane& l = lanes[o.alternate ? (n + k + rep) % lanes.size() : n];
        Technique& t = *l.t;
        Run& r = l.run;
        t.before_update();
        other.touch();
        Timing upd, out;
        if (!t.idle()) {
          Status st;
          upd = timed([&] { st = t.update(c); });
          if (!st) return Error{st.message()};
        }
        if (t.has_output()) out = timed([&] { t.output(); });
        const FrameFigures f = t.figures();
        r.wall_ms.push_back(upd.wall_ms);
        r.cpu_ms.push_back(upd.cpu_ms);
        r.faults.push_back(double(upd.faults));
        r.output_ms.push_back(out.wall_ms);
        r.output_cpu_ms.push_back(out.cpu_ms);
        r.triangles.push_back(f.triangles);
        push_if(r.changes, f.changes);
        r.memory_bytes.push_back(f.memory_bytes);
        r.data_bytes.push_back(f.data_bytes);
        push_if(r.upload_bytes, f.upload_bytes);
        push_if(r.output_bytes, f.output_bytes);
        Json fj;
        if (o.keep_frames) {
          fj = {{"update_ms", upd.wall_ms},     {"update_cpu_ms", upd.cpu_ms},
                {"page_faults", upd.faults},    {"output_ms", out.wall_ms},
                {"output_cpu_ms", out.cpu_ms},  {"triangles", f.triangles}};
          if (!std::isnan(f.upload_bytes)) fj["upload_bytes"] = f.upload_bytes;
        }
        keep_fields(f.extra, r, o.keep_frames ? &fj : nullptr);

        const auto t_measure = Clock::now();
        if (captured_before(k)) l.before = t.capture(*meter);
        if (measured(k)) {
          // Diagnostics first: the measurement then evicts what they read, as it evicts what
          // the update left, before the next timed update of every technique.
          keep_fields(t.diagnose(c), r, o.keep_frames ? &fj : nullptr);
          const Drawable cur = t.capture(*meter);
          const DrawnMesh mesh = cur(c, false);
          meter->rasterize(mesh, l.now);
          const MeshError e =
              t.view_independent() ? meter->measure_all(l.now) : meter->measure(l.now, c);
          const auto visible = meter->triangles_in_view(mesh, c);
          r.in_view.push_back(double(visible));
          r.max_m.push_back(e.max_m);
          r.rms_m.push_back(e.rms_m);
          r.max_px.push_back(e.max_px);
          r.p99_px.push_back(e.p99_px);
          r.vertices.push_back(double(e.vertices));
          r.uncovered += e.uncovered;
          if (o.keep_frames) {
            fj["triangles_in_view"] = visible;
            fj["max_error"] = e.max_m;
            fj["rms_error"] = e.rms_m;
            fj["max_screen_error_px"] = e.max_px;
            fj["p99_screen_error_px"] = e.p99_px;
            fj["uncovered_vertices"] = e.uncovered;
          }
          if (o.pops && l.before) {
            const Camera& last = path[k - 1];
            // Without geomorphs the camera does not change the drawn mesh: the previous frame's
            // mesh serves both the per-vertex jump and the pop.
            meter->rasterize(l.before(last, false), l.prev);
            r.jump.push_back(meter->jump_px(l.prev, l.now, c, &last));
            r.pop.push_back(meter->jump_px(l.prev, l.now, c, &last));
            if (r.has_morph) {
              meter->rasterize(cur(c, true), l.now_m);
              r.morph_max_px.push_back(meter->measure(l.now_m, c).max_px);
              meter->rasterize(l.before(last, true), l.prev_m);
              r.jump_morph.push_back(meter->jump_px(l.prev_m, l.now_m, c, &last));
              // The pop: both meshes morphed for the current camera, so only the topology
              // differs; over the vertices in view in both frames, like the jump (a region
              // coming into view refines unseen).
              meter->rasterize(l.before(c, true), l.prev_m);
              r.pop_morph.push_back(meter->jump_px(l.prev_m, l.now_m, c, &last));
            }
          }
        }
        r.measure_s += ms_since(t_measure) / 1000;
        if (o.keep_frames) r.frames.push_back(std::move(fj));
      }
    }
  }
  std::vector<Run> runs;
  for (Lane& l : lanes) {
    l.run.summary = l.t->summary();
    l.run.wall_s = ms_since(t_run) / 1000;
    runs.push_back(std::move(l.run));
  }
  return runs;
}

Result<Run> run_path(Technique& technique, const std::vector<Camera>& path,
                     const MeshErrorMeter* meter, const LoopOptions& options) {
  auto runs = run_path(std::vector<Technique*>{&technique}, path, meter, options);
  if (!runs) return runs.error();
  return std::move(runs->front());
}

}  // namespace ridgeline::bench
