// Dear ImGui (Debian's libimgui-dev 1.86, with its GLFW and OpenGL 3 backends): an immediate-mode
// panel is a few lines per figure, which is why the game uses it instead of its own UI.
#include "panel.h"

#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include <cstdio>

#include "materials.h"

namespace game {

Panel::Panel(GLFWwindow* window, int width, int height)
    : window_(window), width_(width), height_(height) {
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // no imgui.ini written next to the game
  ImGui::StyleColorsDark();
  ImGui::GetStyle().Alpha = 0.92f;
  if (window_ != nullptr) ImGui_ImplGlfw_InitForOpenGL(window_, true);
  ImGui_ImplOpenGL3_Init("#version 330 core");
}

Panel::~Panel() {
  ImGui_ImplOpenGL3_Shutdown();
  if (window_ != nullptr) ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
}

bool Panel::wants_keyboard() const {
  return ImGui::GetIO().WantCaptureKeyboard;
}

void Panel::draw(Game& game, RenderSettings& settings, const PanelInput& in, double dt_s) {
  frame_history_.push_back(static_cast<float>(in.frame_ms));
  while (frame_history_.size() > 240) frame_history_.pop_front();
  ImGui_ImplOpenGL3_NewFrame();
  if (window_ != nullptr) {
    ImGui_ImplGlfw_NewFrame();
  } else {
    ImGuiIO& io = ImGui::GetIO();
    io.DisplaySize = ImVec2(float(width_), float(height_));
    io.DeltaTime = dt_s > 0 ? float(dt_s) : 1.0f / 60.0f;
  }
  ImGui::NewFrame();
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(360, 0), ImGuiCond_FirstUseEver);
  if (toggle_) open_ = !open_, toggle_ = false, apply_ = true;
  if (apply_) ImGui::SetNextWindowCollapsed(!open_, ImGuiCond_Always), apply_ = false;
  open_ = ImGui::Begin("Ridgeline - F2: debug panel");
  if (!open_) {  // folded: the title bar alone
    ImGui::End();
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    return;
  }
  const ViewFrame& vf = game.last_view_frame();
  const ridgeline::BudgetController& c = game.controller();
  ImGui::Text("frame %.1f ms  (target %.0f ms, smoothed %.1f)", in.frame_ms, c.desc().target_ms,
              c.state().smoothed_ms);
  std::vector<float> hist(frame_history_.begin(), frame_history_.end());
  char label[64];
  std::snprintf(label, sizeof label, "frame ms (last %zu)", hist.size());
  ImGui::PlotLines("##frames", hist.data(), int(hist.size()), 0, label, 0.0f, 80.0f,
                   ImVec2(340, 60));
  ImGui::Separator();
  ImGui::Text("threshold %.2f px  (%s)", game.threshold(),
              game.controller_on() ? to_string(c.state().action) : "fixed");
  bool on = game.controller_on();
  if (ImGui::Checkbox("budget controller", &on)) game.set_controller_on(on);
  if (!on) {
    float t = float(game.threshold());
    if (ImGui::SliderFloat("threshold px", &t, 0.5f, 16.0f, "%.2f")) game.set_threshold(t);
  }
  float target = float(c.desc().target_ms);
  if (ImGui::SliderFloat("target ms", &target, 10.0f, 100.0f, "%.0f"))
    (void)game.controller().set_target_ms(target);
  int tris = int(game.max_triangles());
  if (ImGui::SliderInt("triangle budget", &tris, int(game.root_triangles()), 400000))
    game.set_max_triangles(std::uint32_t(tris));
  float tess = float(game.tessellation_budget_ms());
  if (ImGui::SliderFloat("tessellation ms", &tess, 0.0f, 30.0f, "%.1f"))
    game.set_tessellation_budget_ms(tess);
  ImGui::Text("triangles %u  splits %u (+%u forced)  merges %u", vf.stats.triangles,
              vf.stats.splits, vf.stats.forced_splits, vf.stats.merges);
  ImGui::Text("render scale %.2f (%d x %d)%s", game.render_scale(), in.render.scene_width,
              in.render.scene_height, game.controller_on() ? "" : " fixed");
  ImGui::Text("tessellation %.2f ms (%s)  upload %.2f ms (%u patches)  draw %.2f ms",
              vf.stats.update_ms,
              vf.stats.stop == ridgeline::StopReason::kConverged        ? "converged"
              : vf.stats.stop == ridgeline::StopReason::kTriangleBudget ? "triangle cap"
                                                                        : "time budget",
              in.render.upload_ms, in.render.patches_uploaded, in.render.draw_ms);
  if (auto ds = game.detail_stats()) {
    const std::uint64_t gen = ds->generated - last_generated_;
    last_generated_ = ds->generated;
    ImGui::Text("detail: %u levels, tiles resident %zu, pending %zu, generated %llu this frame",
                game.terrain().surface().detail_levels(), ds->resident_tiles, ds->pending,
                static_cast<unsigned long long>(gen));
    ImGui::Text("  %.1f MB, %.0f tiles/s, %u splits waiting for tiles",
                double(ds->resident_bytes) / 1048576.0, ds->generated_per_second,
                vf.stats.pending_splits);
  } else {
    ImGui::Text("detail: off (--detail-levels 0)");
  }
  ImGui::Separator();
  int mode = int(game.rig().mode);
  ImGui::RadioButton("free", &mode, 0);
  ImGui::SameLine();
  ImGui::RadioButton("follow", &mode, 1);
  ImGui::SameLine();
  ImGui::RadioButton("map", &mode, 2);
  game.rig().mode = CameraMode(mode);
  ImGui::Checkbox("wireframe", &settings.wireframe);
  ImGui::SameLine();
  ImGui::Checkbox("geomorphs", &settings.geomorph);
  ImGui::Checkbox("cheap fragments", &settings.cheap_fragments);
  ImGui::SameLine();
  ImGui::Checkbox("front to back", &settings.front_to_back);
  ImGui::Text("vehicles %zu  craters %zu  contacts %zu  t = %.1f s", game.vehicles().size(),
              game.craters().size(), game.contacts(), game.time());
  std::size_t asleep = 0;
  for (const auto& [id, b] : game.bodies()) asleep += b.sleeping();
  const ridgeline::bullet::TerrainSyncStats& sync = game.physics().last_sync();
  ImGui::Text("loose bodies %zu (%zu asleep), %zu touching vehicles", game.bodies().size(), asleep,
              game.body_contacts());
  ImGui::Text("Bullet on the Ridgeline shape; last edit sync: %zu woken, %zu lifted",
              sync.bodies_woken, sync.bodies_lifted);
  if (const VehicleEntry* e =
          game.vehicle(game.rig().follow_vehicle >= 0
                           ? game.rig().follow_vehicle
                           : (game.vehicles().empty() ? -1 : game.vehicles().begin()->first))) {
    const Material& m = material(e->body.ground_material());
    ImGui::Text("%s: %.1f m/s on %s (grip x%.2f), %llu collisions, %llu hits", e->name.c_str(),
                e->body.speed(), m.name, m.friction,
                static_cast<unsigned long long>(e->body.collisions),
                static_cast<unsigned long long>(e->body.body_hits));
  }
  ImGui::Separator();
  if (ImGui::Button("reload scripts (F5)")) game.reload_all_scripts();
  ImGui::SameLine();
  ImGui::Text("%zu scripts, %llu errors", game.scripts().size(),
              static_cast<unsigned long long>(game.error_count()));
  if (!game.errors().empty()) {
    const ScriptError& e = game.errors().back();
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.45f, 0.4f, 1.0f));
    ImGui::TextWrapped("%s (frame %llu):\n%s", e.script.c_str(),
                       static_cast<unsigned long long>(e.frame), e.message.c_str());
    ImGui::PopStyleColor();
  }
  if (ImGui::CollapsingHeader("script log")) {
    const auto& lines = game.scripts().log_lines();
    const std::size_t n = lines.size();
    for (std::size_t i = n > 12 ? n - 12 : 0; i < n; ++i) ImGui::TextUnformatted(lines[i].c_str());
  }
  ImGui::End();
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

}  // namespace game
