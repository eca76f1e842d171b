-- ridgeline.budget_controller: frame times in, pixel threshold out (a synthetic series; no clock).
local dt = 1 / 30
-- 5 ms fixed + 60 ms / threshold of rendering + injected load (tests/unit/test_budget_controller).
local function frame_ms(threshold, extra) return 5 + 60 / threshold + extra end

T.case("defaults and state", function()
  local c = ridgeline.budget_controller()
  T.eq(c:threshold(), 2)
  local s = c:state()
  T.eq(s.target_ms, 33); T.eq(s.min, 1); T.eq(s.max, 16)
  T.eq(s.action, "hold"); T.eq(s.updates, 0)
  T.eq(getmetatable(c), "ridgeline.budget_controller")
  T.truthy(tostring(c):find("threshold 2 px", 1, true), tostring(c))
end)

T.case("a 20 ms spike raises the threshold, which comes back", function()
  local c = ridgeline.budget_controller{target_ms = 33, min = 1, max = 16, threshold = 1}
  for _ = 1, 300 do c:update(frame_ms(c:threshold(), 0), dt) end
  local before = c:threshold()
  T.truthy(before > 1.9 and before < 2.45, "settled in the band: " .. before)
  for _ = 1, 150 do c:update(frame_ms(c:threshold(), 20), dt) end
  local peak = c:threshold()
  T.truthy(peak > 4.8, "raised under load: " .. peak)
  T.eq(c:state().at_max, false)
  for _ = 1, 450 do c:update(frame_ms(c:threshold(), 0), dt) end
  local after = c:threshold()
  T.truthy(after > 1.95 and after < 2.38, "back in the band: " .. after)
end)

T.case("range, target, reset", function()
  local c = ridgeline.budget_controller{min = 4, max = 8}
  T.eq(c:threshold(), 4, "the default threshold is moved into the range")
  for _ = 1, 300 do c:update(100, dt) end
  T.eq(c:threshold(), 8); T.eq(c:state().at_max, true)
  c:set_range(2, 6)
  T.eq(c:threshold(), 6)
  c:set_target(16)
  T.eq(c:state().target_ms, 16)
  c:reset(3)
  T.eq(c:threshold(), 3); T.eq(c:state().updates, 0)
end)

T.case("bad input", function()
  T.raises("target_ms -1", ridgeline.budget_controller, {target_ms = -1})
  T.raises("threshold range [8, 2]", ridgeline.budget_controller, {min = 8, max = 2})
  T.raises("initial_threshold 50", ridgeline.budget_controller, {threshold = 50})
  T.raises("unknown field 'targetms'", ridgeline.budget_controller, {targetms = 3})
  T.raises("field 'deadband'", ridgeline.budget_controller, {deadband = "wide"})
  T.raises("headroom_gain -1", ridgeline.budget_controller, {headroom_gain = -1})
  local c = ridgeline.budget_controller()
  T.raises("finite number expected", c.update, c, 0 / 0, dt)
  T.raises("frame time in milliseconds >= 0", c.update, c, -5, dt)
  T.raises("time step in seconds >= 0", c.update, c, 30, -1)
  T.raises("bad argument #2", c.set_range, c, 0, 1)
  T.raises("outside [1, 16]", c.reset, c, 100)
  T.raises("target_ms 0", c.set_target, c, 0)
  T.raises("ridgeline.budget_controller expected", c.update, {}, 30, dt)
  T.eq(c:threshold(), 2, "nothing changed after the errors")
end)

T.case("warm-up: start-up frames do not steer it", function()
  local c = ridgeline.budget_controller{max = 12}
  T.eq(c:state().warming_up, true)
  for _, ms in ipairs{221, 95, 60, 48, 41, 36, 35, 34, 36, 35} do c:update(ms, ms / 1000) end
  T.eq(c:threshold(), 2, "the first 10 frames are not acted on")
  c:update(35, dt)
  T.eq(c:state().warming_up, false)
  T.eq(c:state().updates, 11)
end)

T.case("render scale: the second lever", function()
  -- fill-bound: 6 ms fixed, 8 ms of triangles at 2 px (1 / threshold^2), 22 ms of fill at
  -- full resolution (scale^2), plus 15 ms of load.
  local function fill_ms(t, s, extra) return 6 + 32 / (t * t) + 22 * s * s + extra end
  local c = ridgeline.budget_controller{max = 12, min_render_scale = 0.5, render_scale_from = 3}
  T.eq(c:render_scale(), 1)
  local t, s = c:threshold(), c:render_scale()
  for _ = 1, 300 do t, s = c:update(fill_ms(t, s, 15), dt) end
  T.eq(t, 3, "the threshold waits at the scale's step")
  T.truthy(s < 0.85 and s >= 0.5, "scale " .. s)
  T.eq(c:state().render_scale, s)
  T.truthy(math.abs(fill_ms(t, s, 15) / 33 - 1) < 0.1, "the frame is back near the target")
  for _ = 1, 120 do t, s = c:update(fill_ms(t, s, 0), dt) end
  T.truthy(s > 0.99, "the scale comes back first (into the band): " .. s)
  c:set_render_scale_range(1)
  T.eq(c:state().min_render_scale, 1)
  c:reset(3, 1)
  T.raises("render scale 0.7 outside [1, 1]", c.reset, c, 3, 0.7)
  T.raises("min_render_scale 0", c.set_render_scale_range, c, 0)
  T.raises("min_render_scale 2", ridgeline.budget_controller, {min_render_scale = 2})
  T.raises("render_scale_from_px 40", ridgeline.budget_controller,
           {min_render_scale = 0.5, render_scale_from = 40})
  T.raises("field 'median_frames': integer 1 .. 15", ridgeline.budget_controller,
           {median_frames = 2.5})
  T.raises("median_frames 4", ridgeline.budget_controller, {median_frames = 4})
  T.raises("field 'warmup_frames': integer 0 .. 1000", ridgeline.budget_controller,
           {warmup_frames = -1})
end)
