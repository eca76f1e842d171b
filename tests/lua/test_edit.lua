-- terrain:deform and ridgeline.save_edits / load_edits (docs/lua_api.md, "Deformation").
local t = ridgeline.default_terrain()  -- 1025 x 1025 samples, 2 m apart
local x0, z0 = 1024, 1024                -- a sample in the middle

T.case("crater lowers the surface by its depth at the centre", function()
  local before = t:height(x0, z0)
  local r = assert(t:deform{brush = "crater", x = x0, z = z0, radius = 6, depth = 2, rim = 0.25})
  T.near(t:height(x0, z0), before - 2, 1e-4, "bowl bottom")
  T.truthy(r.samples > 0, "samples changed")
  T.truthy(r.min_x <= x0 - 6 and r.max_x >= x0 + 6, "changed box holds the crater")
  T.truthy(r.min_y <= before - 2 + 1e-4, "changed box spans the new heights")
  T.eq(r.clipped, false); T.eq(r.clamped, false)
  -- raycasts see it at once
  local d, hx, hy, hz = t:raycast(x0, 1000, z0, 0, -1, 0, 5000)
  T.near(hy, t:height(x0, z0), 1e-4, "ray hits the crater floor")
end)

T.case("every brush, and a brush outside the terrain", function()
  for _, b in ipairs{"raise", "lower", "flatten", "smooth"} do
    local r = assert(t:deform{brush = b, x = x0, z = z0, radius = 5, strength = 0.5, depth = 1, height = 100})
    T.truthy(r.samples >= 0, b)
  end
  local r = assert(t:deform{brush = "crater", x = -5000, z = 0, radius = 3})
  T.eq(r.samples, 0, "outside: nothing changed"); T.eq(r.min_x, nil, "no box")
end)

T.case("a hole: no ground, rays through, filled back", function()
  local x, z = 501, 301                   -- the centre of cell (250, 150) (2 m cells)
  local before = t:height(x, z)
  local v0 = t:edit_version()
  local r = assert(t:deform{brush = "hole", x = x, z = z, radius = 3})
  T.eq(r.samples, 0, "no height changed")
  T.truthy(r.hole_cells > 0, "cells made holes")
  T.truthy(r.min_x <= x - 1 and r.max_x >= x + 1, "changed box holds the hole")
  T.eq(t:height(x, z), nil, "no ground over the hole")
  T.eq(t:raycast(x, 1000, z, 0, -1, 0, 5000), nil, "straight down the hole: nothing")
  T.truthy(t:height(x + 6, z), "ground beside it")
  local changes = t:changes_since(v0)
  T.eq(#changes, 1, "one change-log entry")
  r = assert(t:deform{brush = "fill_hole", x = x, z = z, radius = 3})
  T.truthy(r.hole_cells > 0, "cells given back")
  T.eq(t:height(x, z), before, "the ground it had")
end)

T.case("bad edits are refused with the field named", function()
  T.raises("field 'brush'", t.deform, t, {brush = "nuke", x = 0, z = 0, radius = 1})
  T.raises("field 'radius': number expected", t.deform, t, {brush = "crater", x = 0, z = 0})
  T.raises("finite number expected", t.deform, t, {brush = "crater", x = 0 / 0, z = 0, radius = 1})
  T.raises("strength is 3", t.deform, t, {brush = "raise", x = 0, z = 0, radius = 1, strength = 3})
  T.raises("unknown field 'radius_m'", t.deform, t, {brush = "raise", x = 0, z = 0, radius_m = 1})
  T.raises("field 'keep_detail': boolean expected", t.deform, t,
           {brush = "raise", x = 0, z = 0, radius = 1, keep_detail = 1})
  local r, err = t:deform{brush = "crater", x = x0, z = z0, radius = 1e6}
  T.eq(r, nil); T.truthy(err:find("larger than the terrain", 1, true), err)
end)

T.case("save and load paths", function()
  if os and os.tmpname then  -- the stock interpreter: unconfined paths
    local f = os.tmpname()
    local h = t:height(x0, z0)
    assert(ridgeline.save_edits(t, f))
    assert(t:deform{brush = "raise", x = x0, z = z0, radius = 8, depth = 3})
    T.truthy(t:height(x0, z0) > h + 1, "raised")
    local r = assert(ridgeline.load_edits(t, f))
    T.near(t:height(x0, z0), h, 0, "undone by loading the save")
    -- the same as terrain methods
    assert(t:deform{brush = "lower", x = x0, z = z0, radius = 8, depth = 3})
    T.eq(t:save_edits(f .. ".2"), true)
    assert(t:load_edits(f))
    T.near(t:height(x0, z0), h, 0, "terrain:load_edits undoes too")
    assert(t:load_edits(f .. ".2"))
    T.truthy(t:height(x0, z0) < h - 1, "and redoes")
    os.remove(f .. ".2")
    local other = assert(ridgeline.load{heightmap = DATA .. "ramp16.png"})
    local ok, err = ridgeline.load_edits(other, f)
    T.eq(ok, nil); T.truthy(err:find("another terrain", 1, true), err)
    os.remove(f)
  else  -- the sandbox: confined to the data folder
    local ok, err = ridgeline.save_edits(t, "/tmp/x.bin")
    T.eq(ok, nil); T.truthy(err:find("absolute paths are not allowed", 1, true), err)
    ok, err = ridgeline.load_edits(t, "../x.bin")
    T.eq(ok, nil); T.truthy(err:find("'..' is not allowed", 1, true), err)
    ok, err = ridgeline.load_edits(t, "no_such_state.bin")
    T.eq(ok, nil); T.truthy(err:find("No such file", 1, true), err)
    ok, err = t:save_edits("/etc/passwd")
    T.eq(ok, nil); T.truthy(err:find("absolute paths are not allowed", 1, true), err)
    ok, err = t:load_edits("../../x.bin")
    T.eq(ok, nil); T.truthy(err:find("'..' is not allowed", 1, true), err)
  end
  T.raises("NUL", ridgeline.save_edits, t, "a\0b")
  T.raises("ridgeline.terrain expected", ridgeline.save_edits, {}, "x.bin")
end)

T.case("edit_version and changes_since: every edit is a changed box under its version", function()
  local u = ridgeline.default_terrain()  -- shared with the cases above: versions are relative
  local v0 = u:edit_version()
  T.eq(math.type(v0), "integer")
  local changes, v, trimmed = u:changes_since(v0)
  T.eq(#changes, 0, "nothing new"); T.eq(v, v0); T.eq(trimmed, false)
  local x1, x2 = 300, 700
  local r1 = assert(u:deform{brush = "raise", x = x1, z = 500, radius = 10, depth = 3})
  local r2 = assert(u:deform{brush = "crater", x = x2, z = 400, radius = 8, depth = 2})
  assert(u:deform{brush = "crater", x = -5000, z = 0, radius = 3})  -- outside: no change
  T.eq(u:edit_version(), v0 + 2, "two edits changed heights")
  changes, v, trimmed = u:changes_since(v0)
  T.eq(v, v0 + 2); T.eq(trimmed, false); T.eq(#changes, 2, "one entry per edit")
  for k, r in ipairs{r1, r2} do
    local c = changes[k]
    T.eq(c.version, v0 + k, "version of entry " .. k)
    for _, f in ipairs{"min_x", "min_y", "min_z", "max_x", "max_y", "max_z"} do
      T.eq(c[f], r[f], f .. " of entry " .. k .. " is the deform result's")
    end
    -- lattice indices (2 m spacing, no detail): the changed samples
    T.eq(math.type(c.i0), "integer")
    T.truthy(c.i0 <= c.i1 and c.j0 <= c.j1, "vertex range")
    T.truthy(c.min_x <= c.i0 * 2 and c.max_x >= c.i1 * 2, "box holds the vertex range")
  end
  T.truthy(changes[1].min_x < x1 and changes[1].max_x > x1, "the raise's box is around it")
  T.truthy(changes[2].min_x < x2 and changes[2].max_x > x2, "the crater's box is around it")
  changes, v = u:changes_since(v0 + 1)
  T.eq(#changes, 1); T.eq(changes[1].version, v0 + 2); T.eq(v, v0 + 2)
  changes, v = u:changes_since(v)
  T.eq(#changes, 0, "nothing after the current version")
  -- a version the terrain never had: the whole footprint, trimmed
  local min_x, _, max_x = u:bounds()
  changes, v, trimmed = u:changes_since(v0 + 99)
  T.eq(#changes, 1); T.eq(trimmed, true); T.eq(v, v0 + 2)
  T.eq(changes[1].min_x, min_x); T.eq(changes[1].max_x, max_x)
  T.raises("version >= 0 expected", u.changes_since, u, -1)
  T.raises("number has no integer representation", u.changes_since, u, 1.5)
  T.raises("number expected", u.changes_since, u)
  u:release()
  T.raises("released", u.edit_version, u)
  T.raises("released", u.changes_since, u, 0)
end)

T.case("keep_detail = false: refused over procedural detail, the same edit without", function()
  local d = assert(ridgeline.load{heightmap = DATA .. "ramp16.png", spacing = 8, detail_levels = 3})
  local h = d:height(12, 12)
  local r, err = d:deform{brush = "flatten", x = 12, z = 12, radius = 10, height = 5,
                          keep_detail = false}
  T.eq(r, nil); T.truthy(err:find("keep_detail = false is not supported", 1, true), err)
  T.eq(d:height(12, 12), h, "nothing changed"); T.eq(d:edit_version(), 0)
  assert(d:deform{brush = "flatten", x = 12, z = 12, radius = 10, height = 5})  -- detail kept
  T.eq(d:edit_version(), 1)
  local plain = ridgeline.default_terrain()
  assert(plain:deform{brush = "flatten", x = 800, z = 800, radius = 10, height = 5,
                      keep_detail = false})
  T.near(plain:height(800, 800), 5, 1e-4, "without detail there is nothing to keep")
end)

T.case("heights over a rectangle: get, set, errors", function()
  local r = ridgeline.default_terrain()
  local before = assert(r:get_heights{i0 = 100, j0 = 200, width = 3, height = 2})
  T.eq(#before, 6, "3 x 2 heights")
  T.near(before[1], r:height(200, 400), 1e-3, "sample (100, 200) at x 200, z 400 (2 m spacing)")
  local v = r:edit_version()
  local res = assert(r:set_heights{i0 = 100, j0 = 200, width = 3, height = 2,
                                   heights = {10, 11, 12, 13, 14, 15}})
  T.eq(res.samples, 6)
  T.eq(r:edit_version(), v + 1, "one edit")
  T.near(r:height(202, 402), 14, 1e-4, "sample (101, 201) is the fifth value")
  local back = r:get_heights{i0 = 100, j0 = 200, width = 3, height = 2}
  for k = 1, 6 do T.near(back[k], 9 + k, 1e-4, "value " .. k) end
  local t2, err = r:get_heights{i0 = 1024, j0 = 0, width = 2, height = 1}
  T.eq(t2, nil); T.truthy(err:find("pass the stored 1025 x 1025", 1, true), err)
  T.raises("field 'heights': 2 values for 3 x 2 samples", r.set_heights, r,
           {i0 = 0, j0 = 0, width = 3, height = 2, heights = {1, 2}})
  T.raises("field 'heights': 7 values for 3 x 2 samples", r.set_heights, r,
           {i0 = 0, j0 = 0, width = 3, height = 2, heights = {1, 2, 3, 4, 5, 6, 7}})
  T.raises("field 'heights': value 2 is not a number", r.set_heights, r,
           {i0 = 0, j0 = 0, width = 2, height = 1, heights = {1, "x"}})
  T.raises("field 'width': whole number >= 0 expected", r.get_heights, r,
           {i0 = 0, j0 = 0, width = 1.5, height = 1})
  T.raises("1000 x 1000 samples: at most 65536 per call", r.get_heights, r,
           {i0 = 0, j0 = 0, width = 1000, height = 1000})
  r:release()
end)
