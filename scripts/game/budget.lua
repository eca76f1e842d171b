-- Budget: the LOD controller holds the frame time near 33 ms. Its ladder of quality (one
-- integrator, docs/game.md "LOD budget controller"): the pixel threshold from 1.5 to 6 px, then
-- the render scale from 1 down to 0.5 (the scene renders into a smaller framebuffer and is
-- upscaled), then the threshold on up to 12 px; back down in the reverse order. On llvmpipe
-- triangles cost more than pixels and the upscale itself costs a full-screen pass, so the
-- threshold goes first (docs/game.md, "Where the frame goes"). The triangle budget is sized for
-- a software renderer; the tessellation time budget keeps one view update within 8 ms.
-- The hysteresis band is 4 % of the target (the library's default is 8 %): the controller stops
-- where the smoothed frame time enters the band, so a narrower band settles closer to 33 ms and
-- spends the headroom on detail (docs/game.md, "LOD budget controller").
game.set_budget{controller = true, target_ms = 33, deadband = 0.04, min = 1.5, max = 12,
                min_scale = 0.5, scale_from = 6, triangles = 80000, tess_ms = 8}

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
