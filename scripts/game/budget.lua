-- Budget: the LOD controller holds the frame time near 33 ms by moving the pixel threshold
-- between 1 and 12 pixels, under a triangle budget sized for a software renderer.
game.set_budget{controller = true, target_ms = 33, min = 1, max = 12, triangles = 60000,
                tess_ms = 8}

local last_report = 0
game.on("tick", function(dt, t)
  if t - last_report < 5 then return end
  last_report = t
  local b, s = game.budget(), game.stats()
  game.log(("budget: %.1f ms (smoothed %.1f), threshold %.2f px, %d triangles"):format(
    s.frame_ms, b.smoothed_ms, b.threshold, s.triangles))
end)
