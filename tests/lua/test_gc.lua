-- Garbage collection: 10^5 objects created and dropped without growth (leaks are caught by the
-- sanitizer build; here the Lua heap must return to where it started).
collectgarbage("collect")
local base = collectgarbage("count")
local d = ridgeline.default_terrain()
-- Each call is a fresh 6 MB copy: fewer of them, dropped without release().
for i = 1, 300 do
  local t = ridgeline.default_terrain()
  if i % 10 == 0 then T.truthy(t:height(1024, 1024)) end
end
local ramp = assert(ridgeline.load{heightmap = DATA .. "ramp16.png"})
for i = 1, 100000 do
  local r = ramp:heights{1, 1, 2, 2}
  if i % 10 == 0 then local p = ramp:place(2, 1.5, {length = 1, width = 1}) end
end
for i = 1, 2000 do
  local v = ramp:new_view{eye = {2, 50, -10}, target = {2, 0, 2}}
  if i % 100 == 0 then v:update() end
  if i % 3 == 0 then v:release() end
end
for i = 1, 300 do
  local t = assert(ridgeline.load{heightmap = DATA .. "ramp16.png"})
  if i % 2 == 0 then t:release() end
end
d = nil
collectgarbage("collect")
collectgarbage("collect")
local grown = collectgarbage("count") - base
T.truthy(grown < 256, ("Lua heap grew by %.1f KiB"):format(grown))
