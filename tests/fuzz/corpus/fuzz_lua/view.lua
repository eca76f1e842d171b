local t = ridgeline.load{heightmap = "ramp16.png", spacing = 4}
local v = t:new_view{eye = {1024, 300, -200}, target = {1024, 0, 1024}, fov_y = 60, viewport = {320, 200}, triangles = 5000}
v:update()
v:set_camera{eye = {0, 100, 0}, target = {500, 0, 500}}
v:update()
local st = v:stats()
v:release()
