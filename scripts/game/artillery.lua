-- Artillery: every 2 seconds a shell lands 18 .. 45 m from a convoy vehicle (never on it) and
-- opens a crater. A small deterministic generator (not math.random, which Lua seeds at random)
-- keeps runs reproducible.
local interval = 2.0      -- seconds between shells
local next_shot = 1.5
local seed = 12345

local function rand()     -- 0 .. 1, a linear congruential generator
  seed = (seed * 1103515245 + 12345) % 2147483648
  return seed / 2147483648
end

local shells = 0
game.on("tick", function(dt, t)
  if t < next_shot then return end
  next_shot = t + interval
  local targets = CONVOY or game.vehicles()
  if #targets == 0 then return end
  local v = targets[1 + math.floor(rand() * #targets) % #targets]
  if not v:alive() then return end
  local x, _, z = v:position()
  local angle = rand() * 2 * math.pi
  local dist = 18 + rand() * 27
  local cx, cz = x + dist * math.cos(angle), z + dist * math.sin(angle)
  local samples, err = game.crater{x = cx, z = cz, radius = 6 + rand() * 4, depth = 2 + rand() * 2}
  shells = shells + 1
  if not samples then game.log("artillery: " .. err) end
end)

game.on("crater", function(x, z, radius, depth)
  game.log(("crater at (%.0f, %.0f): radius %.1f m, depth %.1f m"):format(x, z, radius, depth))
end)
