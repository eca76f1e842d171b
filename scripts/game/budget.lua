-- Budget: the LOD controller holds the frame time near 33 ms. Its ladder of quality (one
-- integrator, docs/game.md "LOD budget controller"): the pixel threshold from 1.5 to 4 px, then
-- the render scale from 1 down to 0.5 (the scene renders into a smaller framebuffer and is
-- upscaled), then the threshold on up to 12 px; back down in the reverse order. The picture stays
-- at full resolution while the frame budget allows: on this machine's llvmpipe at 1280 x 720 the
-- default scenario at 2 px and render scale 1 takes about 31 ms (docs/game.md, "Where the frame
-- goes"), so the controller finds its target between 1.5 and 4 px and upscales only under load
-- (an upscaled picture is blurred, coarser geometry at 2-4 px hardly shows). The hysteresis band
-- is the library's 8 %, and the headroom in its lower half is spent slowly (headroom = 2): the
-- frame time hardly changes between 1.6 and 2.8 px, so a controller that stopped where it
-- entered the band would keep whatever threshold it had then. The triangle budget is a safety
-- net above what the 1.5 px floor needs (~80,000 triangles at 1.6 px), so the view stops
-- converged, not at its cap; the tessellation time budget keeps one view update within 8 ms.
game.set_budget{controller = true, target_ms = 33, deadband = 0.08, headroom = 2,
                min = 1.5, max = 12, min_scale = 0.5, scale_from = 4,
                triangles = 120000, tess_ms = 8}

local last_report = 0
game.on("tick", function(dt, t)
  if t - last_report < 5 then return end
  last_report = t
  local b, s = game.budget(), game.stats()
  game.log(("budget: %.1f ms (smoothed %.1f), threshold %.2f px, render scale %.2f, "
            .. "%d triangles, detail tiles %d resident"):format(
    s.frame_ms, b.smoothed_ms, b.threshold, b.render_scale, s.triangles,
    s.tiles_resident or 0))
end)
