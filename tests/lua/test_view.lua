-- ridgeline.view: the ROAM mesh of one camera over the default terrain.
local t = ridgeline.default_terrain()
local cam = {eye = {1024, 300, -200}, target = {1024, 0, 1024}, fov_y = 60, viewport = {1280, 720}}

T.case("update and stats", function()
  local v = t:new_view(cam)
  T.eq(v:stats(), nil, "no stats before the first update")
  T.eq(v:threshold(), 2, "default threshold, pixels")
  local s = v:update()
  T.truthy(s.triangles > 100, "some triangles: " .. s.triangles)
  T.eq(s.stop, "converged")
  T.truthy(s.max_remaining_error <= 2 + 1e-9, "converged below the threshold")
  T.truthy(s.update_ms >= 0 and s.memory_bytes > 0)
  T.eq(v:stats().triangles, s.triangles, "stats() repeats the last update")
  T.truthy(tostring(v):find("triangles", 1, true))
  T.eq(getmetatable(v), "ridgeline.view")
end)

T.case("threshold and budget", function()
  local v = t:new_view(cam)
  local fine = v:update().triangles
  v:set_threshold(16)
  T.eq(v:threshold(), 16)
  local coarse = v:update().triangles
  T.truthy(coarse < fine, ("coarser at 16 px: %d < %d"):format(coarse, fine))
  v:set_threshold(0.5)
  v:set_budget{triangles = 2000}
  local s = v:update()
  T.truthy(s.triangles <= 2000, "triangle budget holds: " .. s.triangles)
  T.eq(s.stop, "triangle_budget")
  local tri, ms = v:budget()
  T.eq(tri, 2000); T.eq(ms, 0)
  v:set_budget{triangles = 0, ms = 5}
  tri, ms = v:budget()
  T.eq(tri, 4000000, "0 means the binding's cap"); T.eq(ms, 5)
  local w = t:new_view{eye = {0, 500, 0}, target = {1024, 0, 1024}, threshold = 4, triangles = 5000}
  T.eq(w:threshold(), 4); T.eq((w:budget()), 5000)
end)

T.case("set_camera", function()
  local v = t:new_view(cam)
  v:update()
  v:set_camera{eye = {1024, 300, 2300}}  -- other fields kept
  local s = v:update()
  T.truthy(s.triangles > 100)
  T.raises("camera: ", v.set_camera, v, {eye = {1024, 0, 1024}})  -- eye == target
  -- One "camera: " prefix, as validate_camera words it (it was doubled).
  local ok, err = pcall(v.set_camera, v, {eye = {1024, 0, 1024}})
  T.truthy(not ok and err:find("(camera: eye and target are the same point)", 1, true), err)
  T.truthy(not err:find("camera: camera:", 1, true), "doubled prefix: " .. err)
  ok, err = pcall(function() return t:new_view{fov_y = 200} end)
  T.truthy(not ok and err:find("bad argument #1 to 'new_view' (camera: fov_y ", 1, true), err)
  T.raises("field 'fov_y': number expected, got string", v.set_camera, v, {fov_y = "wide"})
  T.raises("field 'eye': array of 3 numbers expected", v.set_camera, v, {eye = {1, 2}})
  T.raises("field 'eye': entry 2: finite number expected, got nan", v.set_camera, v, {eye = {1, 0 / 0, 3}})
  T.raises("unknown field 'threshold'", v.set_camera, v, {threshold = 3})
  T.raises("field 'viewport': {width, height} in 1 .. 65536 pixels expected",
           v.set_camera, v, {viewport = {0, 10}})
  T.raises("camera: ", function() return t:new_view{fov_y = 200} end)
  T.raises("bad argument #1 to 'set_threshold' (threshold in pixels >= 0 expected)",
           function() return v:set_threshold(-1) end)
  T.raises("bad argument #1 to 'set_threshold' (number expected, got no value)",
           function() return v:set_threshold() end)
  T.raises("field 'ms': milliseconds in 0 .. 60000 expected", v.set_budget, v, {ms = -1})
  T.raises("ridgeline.view expected, got", v.update, t)
end)

T.case("release", function()
  local v = t:new_view(cam)
  v:release()
  T.raises("attempt to use a released ridgeline.view", v.update, v)
  T.truthy(tostring(v):find("released", 1, true))
  -- A view keeps its terrain data alive after the terrain is released.
  local own = ridgeline.default_terrain()
  local w = own:new_view(cam)
  own:release()
  T.truthy(w:update().triangles > 0, "view outlives its terrain handle")
  T.raises("attempt to use a released ridgeline.terrain", function() return own:new_view(cam) end)
end)
