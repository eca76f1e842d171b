-- Earthworks: every 3 seconds an engineer reshapes the ground ahead of the convoy with the
-- terrain's own brushes (game.terrain:deform: raise, lower, flatten, smooth, crater), a little
-- off the loop so the convoy drives past the result. Deterministic (no math.random).
-- The game's physics hears of every edit through the terrain (the edit-reaction work); until
-- then the vehicles' own contact step keeps them on the new surface.
local interval = 3.0
local next_edit = 2.5
local brushes = {"raise", "flatten", "lower", "smooth", "crater"}
local count = 0

game.on("tick", function(dt, t)
  if t < next_edit then return end
  next_edit = t + interval
  local lead = CONVOY and CONVOY[1]
  if not (lead and lead:alive()) then return end
  local x, _, z = lead:position()
  local s = lead:state()
  -- 35 m ahead of the lead vehicle, 14 m to the outside of the loop.
  local fx, fz = math.sin(s.heading), math.cos(s.heading)
  local cx, cz = x + 35 * fx + 14 * fz, z + 35 * fz - 14 * fx
  count = count + 1
  local brush = brushes[(count - 1) % #brushes + 1]
  local edit = {brush = brush, x = cx, z = cz, radius = 7}
  if brush == "raise" then edit.depth, edit.strength = 1.5, 1
  elseif brush == "lower" then edit.depth, edit.strength = 1.2, 1
  elseif brush == "flatten" then edit.height, edit.strength = game.terrain:height(cx, cz), 0.8
  elseif brush == "smooth" then edit.strength = 0.7
  else edit.depth, edit.rim = 1.5, 0.2 end
  local r, err = game.terrain:deform(edit)
  if not r then
    game.log("earthworks: " .. err)
  elseif count <= #brushes then
    game.log(("earthworks: %s at (%.0f, %.0f), %d samples"):format(brush, cx, cz, r.samples))
  end
end)
