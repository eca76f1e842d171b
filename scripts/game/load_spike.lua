-- Load spike: from t = 10 s to 15 s every frame burns 20 ms of CPU, as a heavy game system
-- would. The budget controller should raise the pixel threshold to hold its target, then bring
-- it back down afterwards (docs/benchmarks.md, game section).
local from, to = 10, 15
game.on("tick", function(dt, t)
  if t >= from and t < to then game.burn_ms(20) end
end)
