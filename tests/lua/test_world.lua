-- Baked worlds (ridgeline.open_world), raw heightmaps and the size cap from scripts. The data
-- folder holds ramp.png (ramp16.png), ramp.tif (ramp.png baked at 2 m, height 0.5 v - 10,
-- origin 100, 200), noise.tif (a generated 1025 x 1025 world at 1 m) and ramp17x9.r16
-- (value 1000 + 7 i + 100 j at column i, row j); the test registration bakes them.

T.case("a baked world answers as the map it was baked from", function()
  local w = assert(ridgeline.open_world{world = DATA .. "ramp.tif", cache_mb = 8})
  local m = assert(ridgeline.load{heightmap = DATA .. "ramp.png", spacing = 2, height_scale = 0.5,
                                  height_offset = -10, origin = {100, 200}})
  local a = {w:bounds()}
  local b = {m:bounds()}
  for k = 1, 6 do T.eq(a[k], b[k], "bounds " .. k) end
  for x = 100, 108, 0.75 do
    for z = 200, 206, 0.5 do
      T.eq(w:height(x, z), m:height(x, z), ("height at %g, %g"):format(x, z))
    end
  end
  T.eq(w:height(99, 203), nil, "off the world")
  local d, _, y = w:raycast(104, 1000, 203, 0, -1, 0)
  T.truthy(d ~= nil, "the ray hits")
  T.near(y, m:height(104, 203), 1e-9, "a ray meets the stored surface")
  w:release(); m:release()
end)

T.case("a paged world draws, deforms and reports its changes", function()
  local w = assert(ridgeline.open_world{world = DATA .. "noise.tif", cache_mb = 16, workers = 0})
  local x0, z0, x1, z1, y0, y1 = w:bounds()
  T.eq(x1 - x0, 1024, "1025 samples at 1 m"); T.eq(z1 - z0, 1024)
  local v = w:new_view{eye = {512, y1 + 100, 100}, target = {512, y0, 600}, viewport = {640, 360}}
  local s
  for _ = 1, 60 do
    s = v:update()
    if s.stop == "converged" then break end
  end
  T.eq(s.stop, "converged", "the view converges once the pages are in")
  T.truthy(s.triangles > 1000, "a refined mesh: " .. s.triangles)
  local before = w:height(700, 700)
  local version = w:edit_version()
  local r = assert(w:deform{brush = "crater", x = 700, z = 700, radius = 8, depth = 3})
  T.truthy(r.samples > 100, "the crater changed samples")
  T.truthy(w:height(700, 700) < before - 1, "the centre went down")
  local changes = w:changes_since(version)
  T.eq(#changes, 1, "one change")
  T.truthy(changes[1].min_x <= 700 and changes[1].max_x >= 700, "the change covers the crater")
  T.eq(v:update().stop ~= nil, true, "the view follows the edit")
  v:release(); w:release()
end)

T.case("open_world refuses bad input clearly", function()
  local t, err = ridgeline.open_world{world = DATA .. "missing.tif"}
  T.eq(t, nil); T.truthy(err:find("missing.tif", 1, true), err)
  t, err = ridgeline.open_world{world = DATA .. "ramp17x9.r16"}
  T.eq(t, nil); T.truthy(err:find("not a Ridgeline world", 1, true), err)
  T.raises("field 'world': string expected, got number", ridgeline.open_world, {world = 3})
  T.raises("field 'cache_mb': whole number in 4..1048576 expected", ridgeline.open_world,
           {world = DATA .. "noise.tif", cache_mb = 2})
  T.raises("field 'workers': whole number in 0..8 expected", ridgeline.open_world,
           {world = DATA .. "noise.tif", workers = 1.5})
  T.raises("unknown field 'cache'", ridgeline.open_world, {world = DATA .. "noise.tif", cache = 8})
  if not STOCK then
    -- The cache is charged to the object budget before anything is read.
    T.raises("C++ object memory budget exceeded", ridgeline.open_world,
             {world = DATA .. "noise.tif", cache_mb = 4096})
  end
end)

T.case("raw heightmaps load exactly", function()
  local r = assert(ridgeline.load{heightmap = DATA .. "ramp17x9.r16", raw = {width = 17, height = 9}})
  for j = 0, 8 do
    for i = 0, 16 do T.eq(r:height(i, j), 1000 + 7 * i + 100 * j, ("sample %d, %d"):format(i, j)) end
  end
  local t, err = ridgeline.load{heightmap = DATA .. "ramp17x9.r16", raw = {width = 16, height = 9}}
  T.eq(t, nil); T.truthy(err:find("306", 1, true), "names the file's size: " .. err)
  T.raises("field 'raw.type': 'u16' or 'f32' expected", ridgeline.load,
           {heightmap = DATA .. "ramp17x9.r16", raw = {width = 17, height = 9, type = "u8"}})
  T.raises("field 'raw.width': whole number >= 2 expected", ridgeline.load,
           {heightmap = DATA .. "ramp17x9.r16", raw = {height = 9}})
  T.raises("field 'raw': table {width=, height=, type=} expected, got string", ridgeline.load,
           {heightmap = DATA .. "ramp17x9.r16", raw = "17x9"})
end)

T.case("the size cap names how to raise it", function()
  local t, err = ridgeline.load{heightmap = DATA .. "ramp17x9.r16", raw = {width = 17, height = 9},
                                max_samples = 100}
  T.eq(t, nil)
  T.truthy(err:find("153 samples exceeds the limit of 100", 1, true), err)
  T.truthy(err:find("ridgeline.load{max_samples = N}", 1, true), err)
  T.truthy(err:find("ridgeline.open_world", 1, true), err)
  T.raises("field 'max_samples': whole number >= 1 expected", ridgeline.load,
           {heightmap = DATA .. "ramp17x9.r16", raw = {width = 17, height = 9}, max_samples = 0.5})
  if STOCK then
    -- The stock interpreter's user is the host: the cap may be raised without limit.
    assert(ridgeline.load{heightmap = DATA .. "ramp17x9.r16", raw = {width = 17, height = 9},
                          max_samples = 2^40})
  else
    -- The sandbox's default: 4097 x 4097 samples, and scripts cannot raise it.
    T.raises("field 'max_samples': 16785410 is above this host's limit 16785409",
             ridgeline.load, {heightmap = DATA .. "ramp17x9.r16", raw = {width = 17, height = 9},
                              max_samples = 4097 * 4097 + 1})
  end
end)
