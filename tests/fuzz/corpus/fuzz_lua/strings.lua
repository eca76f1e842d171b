local s = ("key = value"):match("^(%w+)%s*=%s*(%w+)$")
local r = ("a,b,c"):gsub(",", ";")
for w in ("one two"):gmatch("%a+") do end
local ok = pcall(string.find, ("a"):rep(1000), ".-.-b")
table.sort({3, 1, 2}, function(a, b) return a < b end)
local co = coroutine.wrap(function() coroutine.yield(1) end)
co()
