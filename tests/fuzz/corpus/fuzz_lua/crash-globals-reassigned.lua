local t = ridgelilocal s = ("key = value"):match("^(%w+)%s*=%s*(%w+)$")
local r = ("a,b,c"):gsub(",", ";")
for w in ("one two"):gmatch("%a+") do end
local ok ridgeline= pcall(string.find, ("a"):rep(1000), ".-.-ne.load{heightmap b")
table.s=ort