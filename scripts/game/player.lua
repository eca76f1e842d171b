-- Player drive: arrow keys (or WASD) drive a buggy, space brakes; the camera follows it.
-- Without a keyboard (headless, offscreen) the buggy idles where it stands.
local me = assert(game.spawn{model = "buggy", x = 1100, z = 1300, heading = 0, name = "player"})
game.camera{mode = "follow", vehicle = me, distance = 14}

game.on("tick", function(dt, t)
  if not me:alive() then return end
  local k = game.input()
  local throttle = (k.up and 1 or 0) - (k.down and 1 or 0)
  local steer = (k.left and 1 or 0) - (k.right and 1 or 0)
  me:set_controls{throttle = throttle, steer = steer, brake = k.brake and 1 or 0}
end)
