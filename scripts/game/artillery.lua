-- Artillery: every 2 seconds a shell lands beside the convoy's road, 12 .. 35 m ahead of a convoy
-- vehicle (the lead one four times in five, so the follow camera sees it) and 13 .. 22 m to one
-- side, never on the road. Each crater throws out boulders and debris (Bullet bodies on the
-- terrain, docs/game_scripting.md "Loose bodies"): two are thrown towards the nearest vehicle and
-- bounce and roll into its path, the rest scatter around the rim and roll back into the crater. A
-- small deterministic generator (not math.random, which Lua seeds at random) keeps runs
-- reproducible.
local interval = 2.0      -- seconds between shells
local next_shot = 1.5
local seed = 12345

local function rand()     -- 0 .. 1, a linear congruential generator
  seed = (seed * 1103515245 + 12345) % 2147483648
  return seed / 2147483648
end

local function convoy()
  return CONVOY or game.vehicles()
end

local shells = 0
game.on("tick", function(dt, t)
  if t < next_shot then return end
  next_shot = t + interval
  local targets = convoy()
  if #targets == 0 then return end
  local v = targets[1]
  if rand() >= 0.8 then v = targets[1 + math.floor(rand() * #targets) % #targets] end
  if not v:alive() then return end
  local s = v:state()
  local fx, fz = math.sin(s.heading), math.cos(s.heading)  -- forward
  local rx, rz = fz, -fx                                     -- to one side
  local ahead = 12 + rand() * 23
  local side = (rand() < 0.5 and -1 or 1) * (13 + rand() * 9)
  local cx, cz = s.x + ahead * fx + side * rx, s.z + ahead * fz + side * rz
  local samples, err = game.crater{x = cx, z = cz, radius = 6 + rand() * 4, depth = 2 + rand() * 2}
  shells = shells + 1
  if not samples then game.log("artillery: " .. err) end
end)

-- The crater's ejecta, at the start of the step after it opened.
game.on("crater", function(x, z, radius, depth)
  game.log(("crater at (%.0f, %.0f): radius %.1f m, depth %.1f m"):format(x, z, radius, depth))
  -- The nearest vehicle and where it is heading.
  local near, best = nil, math.huge
  for _, v in ipairs(convoy()) do
    if v:alive() then
      local vx, _, vz = v:position()
      local d = (vx - x) ^ 2 + (vz - z) ^ 2
      if d < best then near, best = v, d end
    end
  end
  for i = 1, 5 do
    local a = rand() * 2 * math.pi
    local px, pz = x + 0.8 * radius * math.cos(a), z + 0.8 * radius * math.sin(a)
    local py = game.terrain:height(px, pz)
    local vel
    if near and i <= 2 then
      -- Thrown towards the vehicle: it comes down two thirds of the way to where the vehicle will
      -- be in two seconds, and bounces and rolls the rest (a nudge, not a missile).
      local s = near:state()
      local ahead = 2 * s.speed
      local tx = s.x + math.sin(s.heading) * ahead + (rand() - 0.5) * 4
      local tz = s.z + math.cos(s.heading) * ahead + (rand() - 0.5) * 4
      local t = 1.1
      vel = {(tx - px) * 0.65 / t, 5 + rand(), (tz - pz) * 0.65 / t}
    else
      -- Out over the rim, to roll back down the crater's wall.
      local out = 3 + rand() * 3
      vel = {math.cos(a) * out, 4 + rand() * 3, math.sin(a) * out}
    end
    local spin = {rand() * 6 - 3, rand() * 6 - 3, rand() * 6 - 3}
    if py then
      if i % 2 == 1 then
        game.spawn_body{shape = "sphere", x = px, z = pz, y = py + 1.5, radius = 0.3 + rand() * 0.3,
                        velocity = vel, spin = spin, name = "boulder"}
      else
        local w = 0.4 + rand() * 0.6
        game.spawn_body{shape = "box", x = px, z = pz, y = py + 1.5,
                        size = {w, 0.3 + rand() * 0.3, 0.4 + rand() * 0.6}, velocity = vel,
                        spin = spin, name = "debris"}
      end
    end
  end
end)

game.on("hit", function(vehicle, body, speed)
  if speed > 4 then
    local v = game.vehicle(vehicle)
    game.log(("%s hit by %s at %.1f m/s"):format(v and v:state().name or "a vehicle",
                                                  game.body(body) and game.body(body):state().name
                                                  or "a body", speed))
  end
end)
