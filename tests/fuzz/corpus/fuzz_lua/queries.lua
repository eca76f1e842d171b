local t = ridgeline.load{heightmap = "ramp16.png", spacing = 4}
local h = t:height(100, 200)
local nx, ny, nz = t:normal(100, 200)
local s = t:sample(10, 10)
local d = t:raycast(0, 500, 0, 1, -1, 1, 5000)
local hs = t:heights{1, 2, 3, 4, 5, 6}
local p = t:place(300, 420, {length = 4, width = 2, heading = 0.5})
local c = t:contacts(300, 420, 0, {{-1, 1}, {1, 1}})
local x0, z0, x1, z1 = t:bounds()
