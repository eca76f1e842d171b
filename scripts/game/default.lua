-- Default scenario: a convoy of four vehicles follows a loop of waypoints over the hills in the
-- middle of the default terrain while an artillery battery drops craters near it.
-- (docs/game_scripting.md walks through this file.)

-- The loop: 48 points on a circle around the terrain's centre, 380 m across on the default
-- terrain (2,048 m a side) and a fifth of the side on smaller worlds (ridgeline_game --world).
local x0, z0, x1, z1 = game.terrain:bounds()
local cx, cz = (x0 + x1) / 2, (z0 + z1) / 2
local radius = math.min(380, 0.19 * math.min(x1 - x0, z1 - z0))
local waypoints = {}
for i = 0, 47 do
  local a = i / 48 * 2 * math.pi
  waypoints[#waypoints + 1] = {cx + radius * math.sin(a), cz + radius * math.cos(a)}
end

-- The convoy starts behind the first waypoint, nose to tail, heading along the loop (+x).
local convoy = {}
local models = {"truck", "buggy", "truck", "buggy"}
for i, model in ipairs(models) do
  local v, err = game.spawn{model = model, x = cx - 16 * i, z = cz + radius, heading = math.pi / 2,
                            name = model .. " " .. i}
  assert(v, err)
  -- Each one aims a little behind the vehicle ahead by starting at the same waypoint.
  v:follow{waypoints = waypoints, speed = 10 + (i % 2), loop = true, reach = 14}
  convoy[i] = v
end

-- The chase camera: behind and above the lead truck, looking at the road ahead of it, where the
-- artillery's craters open and their boulders come down.
game.camera{mode = "follow", vehicle = convoy[1], distance = 16, lift = 6, ahead = 18}
game.log("convoy of " .. #convoy .. " vehicles on a " .. #waypoints .. "-point loop")

-- Expose the convoy to the other scripts (artillery, budget) through a shared global.
CONVOY = convoy

game.on("waypoint", function(id, next_index)
  if id == convoy[1]:id() and next_index == 1 then game.log("the lead vehicle finished a lap") end
end)
