-- terrain:place and terrain:contacts on an exact plane (ramp16.png, see test_terrain.lua) and on
-- the default terrain.
local t = assert(ridgeline.load{heightmap = DATA .. "ramp16.png", spacing = 2, height_scale = 0.5,
                                height_offset = -10, origin = {100, 200}})
local function h(x, z) return -10 + 0.5 * (1000 + 50 * (x - 100) + 5 * (z - 200)) end
local function dot(a, b) return a[1] * b[1] + a[2] * b[2] + a[3] * b[3] end

T.case("place on a plane", function()
  local p = t:place(104, 203, {length = 2, width = 2, heading = 0})
  T.near(p.y, h(104, 203), 1e-9, "rests on the plane")
  T.eq(p.x, 104); T.eq(p.z, 203)
  local len = math.sqrt(25 * 25 + 1 + 2.5 * 2.5)
  T.near(p.up[1], -25 / len, 1e-9, "up x"); T.near(p.up[2], 1 / len, 1e-9, "up y")
  T.near(p.up[3], -2.5 / len, 1e-9, "up z")
  local fl = math.sqrt(1 + 2.5 * 2.5)
  T.near(p.forward[1], 0, 1e-12); T.near(p.forward[2], 2.5 / fl, 1e-9); T.near(p.forward[3], 1 / fl, 1e-9)
  T.near(p.pitch, math.atan(2.5), 1e-9, "nose up along +z")
  for _, v in ipairs{p.forward, p.up, p.right} do T.near(dot(v, v), 1, 1e-12, "unit") end
  T.near(dot(p.forward, p.up), 0, 1e-12); T.near(dot(p.forward, p.right), 0, 1e-12)
  T.near(dot(p.up, p.right), 0, 1e-12)
  T.truthy(p.right[1] < 0, "right of +z is -x in a right-handed Y-up frame")
end)

T.case("heading turns counterclockwise from above", function()
  local p = t:place(104, 203, {length = 2, width = 1, heading = math.pi / 2})
  T.truthy(p.forward[1] > 0.03 and math.abs(p.forward[3]) < 1e-9, "heading pi/2 points along +x")
  T.near(p.heading, math.pi / 2, 0)
  T.near(p.pitch, math.atan(25), 1e-9, "steeper along x")
end)

T.case("place misses and bad input", function()
  local p, err = t:place(101, 203, {length = 8, width = 1})
  T.eq(p, nil); T.eq(err, "footprint leaves the terrain")
  T.raises("field 'length': number in (0, 1e6] metres expected", t.place, t, 104, 203, {width = 1})
  T.raises("field 'width': number in (0, 1e6] metres expected", t.place, t, 104, 203, {length = 1, width = -1})
  T.raises("unknown field 'heading_deg'", t.place, t, 104, 203, {length = 1, width = 1, heading_deg = 3})
  T.raises("bad argument #3 to 'place' (table expected, got no value)", function() return t:place(104, 203) end)
end)

T.case("place rests on a bumpy surface", function()
  local d = ridgeline.default_terrain()
  for i = 1, 50 do
    local x, z, hd = 100 + i * 37, 200 + i * 29, i * 0.7
    local p = assert(d:place(x, z, {length = 4.5, width = 2, heading = hd}))
    -- No point of the footprint's 3 x 3 grid is above the box's bottom plane.
    for a = -1, 1 do
      for b = -1, 1 do
        local u, v = a * 1, b * 2.25
        local wx = x + u * math.cos(hd) + v * math.sin(hd)
        local wz = z - u * math.sin(hd) + v * math.cos(hd)
        local plane = p.y + ((wx - x) * -p.up[1] + (wz - z) * -p.up[3]) / p.up[2]
        T.truthy(d:height(wx, wz) <= plane + 1e-6, "surface below the box bottom")
      end
    end
  end
end)

T.case("contacts", function()
  local wheels = {{-1, -1.5}, {1, -1.5}, {-1, 1.5}, {1, 1.5}}
  local c = t:contacts(104, 203, 0, wheels)
  T.eq(#c, 4)
  for i, w in ipairs(wheels) do
    T.near(c[i].x, 104 + w[1], 1e-9); T.near(c[i].z, 203 + w[2], 1e-9)
    T.near(c[i].y, h(104 + w[1], 203 + w[2]), 1e-6, "wheel height")
    T.truthy(c[i].ny > 0, "normal up")
  end
  c = t:contacts(104, 203, math.pi / 2, {{0, 1}})
  T.near(c[1].x, 105, 1e-9, "forward offset turns to +x"); T.near(c[1].z, 203, 1e-9)
  c = t:contacts(104, 203, 0, {{0, 0}, {50, 0}})
  T.truthy(c[1], "on terrain"); T.eq(c[2], false, "off terrain")
  T.eq(#t:contacts(104, 203, 0, {}), 0)
  local many = {}
  for i = 1, 65 do many[i] = {0, 0} end
  T.raises("at most 64 offsets per call, got 65", t.contacts, t, 104, 203, 0, many)
  T.raises("offset 2: {x, z} of finite numbers expected", t.contacts, t, 104, 203, 0, {{0, 0}, {0, "a"}})
  T.raises("bad argument #3 to 'contacts' (finite number expected, got nan)",
           function() return t:contacts(104, 203, 0 / 0, wheels) end)
end)
