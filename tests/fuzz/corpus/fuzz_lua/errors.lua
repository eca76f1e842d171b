pcall(error, setmetatable({}, {__tostring = function() return "x" end}))
xpcall(function() error("e") end, function(m) return m end)
local f = load("return 1 + ", "c")
while true do end
