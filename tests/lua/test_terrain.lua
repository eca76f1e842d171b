-- ridgeline.terrain: loading, queries, batched heights, errors, release.
-- ramp16.png is 5 x 4 samples, value(i, j) = 1000 + 100 i + 10 j: a plane, so every query has an
-- exact answer. Loaded with spacing 2, scale 0.5, offset -10, origin (100, 200):
-- h(x, z) = -10 + 0.5 (1000 + 50 (x - 100) + 5 (z - 200)).
local function ramp()
  local t, err = ridgeline.load{heightmap = DATA .. "ramp16.png", spacing = 2, height_scale = 0.5,
                                height_offset = -10, origin = {100, 200}}
  T.truthy(t, "load: " .. tostring(err))
  return t
end
local function h(x, z) return -10 + 0.5 * (1000 + 50 * (x - 100) + 5 * (z - 200)) end

T.case("load and height", function()
  local t = ramp()
  T.near(t:height(102, 202), 545, 1e-9, "height at a sample")
  T.near(t:height(101.3, 203.7), h(101.3, 203.7), 1e-9, "height between samples")
  T.eq(t:height(99, 202), nil, "off terrain")
  T.eq(t:height(108.5, 202), nil, "past the far edge")
  T.near(t:height(108, 206), h(108, 206), 1e-9, "on the far corner")
  local x0, z0, x1, z1, lo, hi = t:bounds()
  T.eq(x0, 100); T.eq(z0, 200); T.eq(x1, 108); T.eq(z1, 206)
  T.near(lo, h(100, 200), 1e-9, "min height"); T.near(hi, h(108, 206), 1e-9, "max height")
  T.truthy(tostring(t):find("5 x 4 samples", 1, true), "tostring")
  T.eq(getmetatable(t), "ridgeline.terrain", "protected metatable")
end)

T.case("normals", function()
  local t = ramp()
  local len = math.sqrt(25 * 25 + 1 + 2.5 * 2.5)
  local nx, ny, nz = t:normal(103.1, 202.7)
  T.near(nx, -25 / len, 1e-6, "nx"); T.near(ny, 1 / len, 1e-6, "ny"); T.near(nz, -2.5 / len, 1e-6, "nz")
  nx, ny, nz = t:smooth_normal(103.1, 202.7)
  T.near(nx, -25 / len, 1e-6, "smooth nx"); T.near(ny, 1 / len, 1e-6, "smooth ny")
  T.eq(t:normal(0, 0), nil, "normal off terrain")
  T.eq(t:smooth_normal(0, 0), nil, "smooth normal off terrain")
  local s = t:sample(103, 203)
  T.near(s.height, h(103, 203), 1e-9, "sample height"); T.near(s.normal[1], -25 / len, 1e-6)
  T.eq(s.material, 0, "no material layer")
  T.eq(t:sample(0, 0), nil, "sample off terrain")
end)

T.case("raycast", function()
  local t = ramp()
  local d, x, y, z, nx, ny, nz = t:raycast(102, 1000, 202, 0, -1, 0, 1e4)
  T.near(d, 1000 - 545, 1e-6, "distance"); T.near(x, 102, 1e-9); T.near(y, 545, 1e-6)
  T.near(z, 202, 1e-9); T.truthy(ny > 0 and nx < 0 and nz < 0, "normal points up the slope")
  T.eq(t:raycast(102, 1000, 202, 0, 1, 0, 1e4), nil, "ray up misses")
  T.eq(t:raycast(102, 1000, 202, 0, -1, 0, 10), nil, "surface beyond max")
  T.truthy(t:raycast(102, 1000, 202, 0, -1, 0), "max defaults to infinity")
  T.truthy(t:raycast(102, 1000, 202, 0, -1, 0, math.huge), "max = math.huge")
  T.raises("bad argument #7 to 'raycast' (number or math.huge expected, got nan)",
           function() return t:raycast(102, 1000, 202, 0, -1, 0, 0 / 0) end)
end)

T.case("batched heights", function()
  local t = ramp()
  local out = t:heights{102, 202, 0, 0, 101, 201}
  T.eq(#out, 3, "one height per point")
  T.near(out[1], 545, 1e-9); T.truthy(out[2] ~= out[2], "NaN off terrain")
  T.near(out[3], h(101, 201), 1e-9)
  local nan = t:heights{0 / 0, 202}
  T.truthy(nan[1] ~= nan[1], "non-finite coordinates give NaN")
  local reuse = {}
  T.eq(t:heights({102, 202}, reuse), reuse, "the out table is reused")
  local big = {}
  for i = 1, 2 * 1000 do big[i] = 100 + (i % 9) end
  local r = t:heights(big)
  T.eq(#r, 1000, "one height per point of a batch of 1000 (answered in chunks of 256)")
  for k = 1, 1000 do
    local want = t:height(big[2 * k - 1], big[2 * k])
    T.truthy((want == nil and r[k] ~= r[k]) or r[k] == want, "batch equals single calls")
  end
  T.eq(#t:heights{}, 0, "empty batch")
  T.eq(ridgeline.max_batch_points, 65536)
  local over = {}
  for i = 1, 2 * 65537 do over[i] = 0 end
  T.raises("bad argument #1 to 'heights' (at most 65536 points per call, got 65537)", function() return t:heights(over) end)
  T.raises("flat array of x, z pairs expected, got 3 numbers", t.heights, t, {1, 2, 3})
  T.raises("entry 2: number expected, got string", t.heights, t, {1, "a"})
  T.raises("bad argument #1 to 'heights' (table expected, got number)", function() return t:heights(5) end)
end)

T.case("bad arguments", function()
  local t = ramp()
  T.raises("bad argument #2 to 'height' (number expected, got string)", function() return t:height(1, "a") end)
  T.raises("bad argument #1 to 'height' (number expected, got no value)", function() return t:height() end)
  T.raises("bad argument #2 to 'height' (finite number expected, got nan)", function() return t:height(1, 0 / 0) end)
  T.raises("bad argument #1 to 'normal' (finite number expected, got inf)", function() return t:normal(math.huge, 1) end)
  T.raises("bad argument #3 to 'raycast' (finite number expected, got -inf)",
           function() return t:raycast(1, 2, -math.huge, 0, -1, 0, 10) end)
  T.raises("ridgeline.terrain expected, got number", t.height, 42, 1, 1)
  T.raises("field 'heightmap': string expected, got nil", ridgeline.load, {})
  T.raises("bad argument #1 to 'load' (table expected, got string)", function() return ridgeline.load("x.png") end)
  T.raises("unknown field 'spacin'", ridgeline.load, {heightmap = "x.png", spacin = 2})
  T.raises("field 'spacing': number expected, got string", ridgeline.load, {heightmap = "x.png", spacing = "2"})
  T.raises("field 'origin': array of 2 numbers expected", ridgeline.load, {heightmap = "x.png", origin = {1}})
  T.raises("field 'height_scale': finite number expected, got inf",
           ridgeline.load, {heightmap = "x.png", height_scale = math.huge})
  T.raises("field 'fill': 'refuse', 'nearest' or 'hole' expected", ridgeline.load, {heightmap = "x.png", fill = "zero"})
  T.raises("field 'alpha_nodata': boolean expected", ridgeline.load, {heightmap = "x.png", alpha_nodata = 1})
end)

T.case("expected misses return nil, message", function()
  local t, err = ridgeline.load{heightmap = DATA .. "no_such_file.png"}
  T.eq(t, nil, "missing file")
  T.truthy(err:find("no_such_file.png", 1, true), "message names the file: " .. err)
  t, err = ridgeline.load{heightmap = DATA .. "ramp16.png", spacing = -1}
  T.eq(t, nil, "bad spacing"); T.truthy(err:find("spacing", 1, true), "message names spacing: " .. err)
  for _, s in ipairs{1e-300, 1e-7, 2e6} do
    t, err = ridgeline.load{heightmap = DATA .. "ramp16.png", spacing = {1, s}}
    T.eq(t, nil, "absurd spacing " .. s)
    T.truthy(err:find("is outside 1e-6 .. 1e6 m", 1, true), "message gives the range: " .. err)
  end
  T.truthy(ridgeline.load{heightmap = DATA .. "ramp16.png", spacing = 1e-6}, "a micrometre")
  t, err = ridgeline.load{heightmap = DATA .. "rgb8.png"}
  T.eq(t, nil, "three channels"); T.truthy(#err > 0)
end)

T.case("default terrain", function()
  local t = ridgeline.default_terrain()
  local hh = t:height(1024, 1024)
  T.truthy(hh > 16 and hh < 219, "height in the documented range")
  local x0, z0, x1, z1 = t:bounds()
  T.eq(x1 - x0, 2048); T.eq(z1 - z0, 2048)
  T.near(ridgeline.default_terrain():height(1024, 1024), hh, 0, "deterministic")
end)

T.case("default terrain: a fresh terrain per call", function()
  local a = ridgeline.default_terrain()
  local pristine = a:height(1024, 1024)
  assert(a:deform{brush = "crater", x = 1024, z = 1024, radius = 10, depth = 5})
  T.near(a:height(1024, 1024), pristine - 5, 1e-3, "the crater is in the terrain that made it")
  local b = ridgeline.default_terrain()
  T.eq(b:height(1024, 1024), pristine, "another call does not see it")
  assert(b:deform{brush = "raise", x = 500, z = 500, radius = 10, depth = 3, strength = 1})
  T.near(a:height(1024, 1024), pristine - 5, 1e-3, "nor does the first see the second's edit")
  a:release()
  T.eq(ridgeline.default_terrain():height(1024, 1024), pristine, "pristine after release")
  T.truthy(a ~= b and rawequal(a, a), "distinct objects")
end)

T.case("arguments are never coerced", function()
  -- One rule for every function: a number argument must be a Lua number (a numeric string is
  -- refused like any other type), a string argument a string, a boolean field a boolean.
  local t = ramp()
  T.raises("bad argument #1 to 'height' (number expected, got string)", function() return t:height("10", 1) end)
  T.raises("bad argument #2 to 'height' (number expected, got string)", function() return t:height(102, "202") end)
  T.raises("bad argument #1 to 'normal' (number expected, got string)", function() return t:normal("102", 202) end)
  T.raises("bad argument #2 to 'smooth_normal' (number expected, got string)", function() return t:smooth_normal(102, "202") end)
  T.raises("bad argument #1 to 'sample' (number expected, got string)", function() return t:sample("102", 202) end)
  T.raises("bad argument #2 to 'raycast' (number expected, got string)", function() return t:raycast(102, "1000", 202, 0, -1, 0) end)
  T.raises("bad argument #7 to 'raycast' (number expected, got string)", function() return t:raycast(102, 1000, 202, 0, -1, 0, "10") end)
  T.raises("bad argument #1 to 'place' (number expected, got string)", function() return t:place("102", 202, {length = 1, width = 1}) end)
  T.raises("field 'length': number expected, got string", function() return t:place(102, 202, {length = "1", width = 1}) end)
  T.raises("bad argument #3 to 'contacts' (number expected, got string)", function() return t:contacts(102, 202, "0", {}) end)
  T.raises("offset 1: {x, z} of finite numbers expected", function() return t:contacts(102, 202, 0, {{"1", 0}}) end)
  T.raises("entry 1: number expected, got string", function() return t:heights{"102", 202} end)
  T.raises("bad argument #1 to 'save_edits' (string expected, got number)", function() return t:save_edits(123) end)
  T.raises("bad argument #1 to 'load_edits' (string expected, got number)", function() return t:load_edits(123) end)
  T.raises("bad argument #2 to 'save_edits' (string expected, got number)", function() return ridgeline.save_edits(t, 123) end)
  T.raises("field 'x': number expected, got string", function() return t:deform{brush = "raise", x = "1", z = 1, radius = 1} end)
  T.raises("field 'detail_levels': number expected, got string",
           ridgeline.load, {heightmap = DATA .. "ramp16.png", detail_levels = "2"})
  local v = t:new_view{eye = {104, 50, 190}, target = {104, 0, 203}}
  T.raises("bad argument #1 to 'set_threshold' (number expected, got string)", function() return v:set_threshold("2") end)
  T.raises("field 'ms': number expected, got string", function() return v:set_budget{ms = "2"} end)
  local c = ridgeline.budget_controller()
  T.raises("bad argument #1 to 'update' (number expected, got string)", function() return c:update("33", 0.03) end)
  T.raises("bad argument #1 to 'set_target' (number expected, got string)", function() return c:set_target("16") end)
  T.raises("bad argument #2 to 'set_range' (number expected, got string)", function() return c:set_range(1, "8") end)
  T.raises("bad argument #1 to 'reset' (number expected, got string)", function() return c:reset("2") end)
  -- Numbers of either subtype are numbers.
  T.near(t:height(102, 202), t:height(102.0, 202.0), 0, "integers and floats")
end)

T.case("release", function()
  local t = ramp()
  t:release()
  T.raises("attempt to use a released ridgeline.terrain", t.height, t, 102, 202)
  T.raises("attempt to use a released ridgeline.terrain", t.heights, t, {})
  T.truthy(tostring(t):find("released", 1, true), "tostring after release")
  t:release() -- twice is fine
  local kept
  do
    local c <close> = ramp()
    kept = c
    T.truthy(c:height(102, 202), "alive inside the scope")
  end
  T.raises("attempt to use a released ridgeline.terrain", kept.height, kept, 102, 202)
end)

T.case("procedural detail through load", function()
  local t = assert(ridgeline.load{heightmap = DATA .. "ramp16.png", spacing = 8, detail_levels = 3,
                                  detail_seed = 7, detail_amplitude = 0.5})
  local base = assert(ridgeline.load{heightmap = DATA .. "ramp16.png", spacing = 8})
  -- At stored samples the detail is zero; between them the surface differs from the plane.
  T.near(t:height(8, 8), base:height(8, 8), 1e-4, "stored sample")
  local differs = false
  for i = 1, 20 do
    if math.abs(t:height(8 + i * 0.77, 9.3) - base:height(8 + i * 0.77, 9.3)) > 1e-3 then differs = true end
  end
  T.truthy(differs, "detail between the stored samples")
  local again = assert(ridgeline.load{heightmap = DATA .. "ramp16.png", spacing = 8, detail_levels = 3,
                                      detail_seed = 7, detail_amplitude = 0.5})
  T.eq(again:height(13.1, 9.7), t:height(13.1, 9.7), "deterministic")
  T.raises("field 'detail_levels': whole number in 0..12 expected", ridgeline.load,
           {heightmap = DATA .. "ramp16.png", detail_levels = 13})
  local bad, err = ridgeline.load{heightmap = DATA .. "ramp16.png", detail_levels = 2, detail_gain = 3}
  T.eq(bad, nil); T.truthy(err:find("gain is 3", 1, true), err)
  bad, err = ridgeline.load{heightmap = DATA .. "ramp16.png", detail_levels = 2, detail_amplitude = -1}
  T.eq(bad, nil); T.truthy(err:find("amplitude", 1, true), err)
end)

T.case("GeoTIFF placement through load", function()
  if not (STOCK and io and os and os.tmpname) then return end  -- needs a file written here
  -- A 3 x 2 int16 GeoTIFF: UTM 33N, 30 m pixels, tie point (500000, 4100000) at the corner.
  local entries = {
    {256, 3, {3}}, {257, 3, {2}}, {258, 3, {16}}, {259, 3, {1}}, {262, 3, {1}},
    {273, 4, {0}}, {277, 3, {1}}, {278, 3, {2}}, {279, 4, {12}}, {339, 3, {2}},
    {33550, 12, {30, 30, 0}}, {33922, 12, {0, 0, 0, 500000, 4100000, 0}},
    {34735, 3, {1, 1, 0, 2, 1024, 0, 1, 1, 3076, 0, 1, 9001}}}
  local fmt = {[3] = "<I2", [4] = "<I4", [12] = "<d"}
  local size = {[3] = 2, [4] = 4, [12] = 8}
  local data_at = 8 + 2 + 12 * #entries + 4
  local blobs, next_at = {}, data_at
  for k, e in ipairs(entries) do
    if #e[3] * size[e[2]] > 4 then blobs[k] = next_at; next_at = next_at + #e[3] * size[e[2]] end
  end
  entries[6][3][1] = next_at  -- the strip follows the data
  local parts = {"II", string.pack("<I2I4I2", 42, 8, #entries)}
  for k, e in ipairs(entries) do
    local v = {}
    for _, x in ipairs(e[3]) do v[#v + 1] = string.pack(fmt[e[2]], x) end
    v = table.concat(v)
    parts[#parts + 1] = string.pack("<I2I2I4", e[1], e[2], #e[3]) ..
                        (blobs[k] and string.pack("<I4", blobs[k]) or (v .. ("\0"):rep(4 - #v)))
  end
  parts[#parts + 1] = string.pack("<I4", 0)
  for k, e in ipairs(entries) do
    if blobs[k] then for _, x in ipairs(e[3]) do parts[#parts + 1] = string.pack(fmt[e[2]], x) end end
  end
  for _, s in ipairs{10, 20, 30, 40, 50, 60} do parts[#parts + 1] = string.pack("<i2", s) end
  local path = os.tmpname() .. ".tif"
  local f = assert(io.open(path, "wb")); f:write(table.concat(parts)); f:close()
  -- No spacing or origin given: the file's own (sample (0, 0) at the centre of pixel (0, 0),
  -- z = -northing).
  local t = assert(ridgeline.load{heightmap = path})
  local x0, z0, x1, z1 = t:bounds()
  T.eq(x0, 500015); T.eq(z0, -4099985); T.eq(x1 - x0, 60); T.eq(z1 - z0, 30)
  T.eq(t:height(500015, -4099985), 10)
  -- Given ones win.
  t = assert(ridgeline.load{heightmap = path, spacing = 2, origin = {0, 0}})
  x0, z0, x1, z1 = t:bounds()
  T.eq(x0, 0); T.eq(z0, 0); T.eq(x1, 4); T.eq(z1, 2)
  os.remove(path)
end)
