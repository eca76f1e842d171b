local t, err = ridgeline.load{heightmap = "ramp16.png", spacing = {2, 3}, height_scale = 0.5}
local u = ridgeline.load{heightmap = "../x.png"}
if t then t:release() end
