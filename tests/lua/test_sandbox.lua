-- The game-script sandbox, seen from inside (run by the host only). Attacks that end the whole
-- call (runaway loops, memory bombs) are in test_lua_host.cpp, where the host can be checked.
T.case("libraries that are not there", function()
  for _, name in ipairs{"io", "os", "package", "debug", "require", "dofile", "loadfile", "module"} do
    T.eq(_G[name], nil, name)
  end
  T.raises("attempt to index a nil value (global 'io')", function() return io.open("/etc/passwd") end)
  T.raises("attempt to index a nil value (global 'os')", function() return os.execute("true") end)
  T.raises("attempt to call a nil value (global 'require')", function() return require("ridgeline") end)
  T.raises("attempt to index a nil value (global 'package')", function() return package.loadlib("libc.so.6", "system") end)
  T.raises("attempt to index a nil value (global 'debug')", function() return debug.sethook() end)
  T.eq(string.dump, nil, "string.dump")
  for _, name in ipairs{"string", "table", "math", "utf8", "coroutine"} do T.eq(type(_G[name]), "table", name) end
end)

T.case("binary chunks are refused", function()
  T.eq(("").dump, nil, "string.dump is gone from the string methods too")
  -- A binary chunk's header (Lua 5.4 signature, version, format, LUAC_DATA), then garbage.
  local bytecode = "\27Lua\x54\0\x19\x93\r\n\x1a\n\4\8\8" .. ("\0"):rep(64)
  local f, err = load(bytecode)
  T.eq(f, nil); T.truthy(err:find("binary chunk", 1, true), err)
  f, err = load(bytecode, "x", "b")
  T.eq(f, nil, "mode 'b' is overridden"); T.truthy(err:find("binary chunk", 1, true), err)
  T.eq(load("return io")(), nil, "loaded chunks see the sandbox, not the real globals")
  T.eq(load("return dofile")(), nil)
  T.eq(load("return x", "c", "t", {x = 5})(), 5, "an explicit environment still works")
end)

T.case("string metatable and library copies", function()
  T.eq(getmetatable(""), "string", "protected")
  T.raises("attempt to index a string value", function() getmetatable("").__index = {} end)
end)

T.case("tampering with string stays local", function()
  local rep = string.rep
  string.rep = nil
  T.eq(("ab"):rep(2), "abab", "string methods unaffected")
  string.rep = rep
end)

T.case("finalizers and collector controls", function()
  T.raises("__gc metamethods are not allowed in the sandbox", setmetatable, {}, {__gc = function() while true do end end})
  T.raises("invalid option 'stop'", collectgarbage, "stop")
  T.raises("invalid option 'generational'", collectgarbage, "generational")
  T.truthy(collectgarbage("count") > 0)
end)

T.case("deep recursion is contained", function()
  local function f() return 1 + f() end
  local ok, err = pcall(f)
  T.eq(ok, false); T.truthy(tostring(err):find("stack overflow", 1, true) or
                            tostring(err):find("memory", 1, true), tostring(err))
  local function g() return coroutine.wrap(g)() end
  ok, err = pcall(g)
  T.eq(ok, false); T.truthy(tostring(err):find("C stack overflow", 1, true), tostring(err))
  local s = string.rep("(", 300) .. string.rep(")", 300)
  ok, err = pcall(string.find, "x", s)
  T.eq(ok, false)
end)

T.case("path traversal through every call that takes a file name", function()
  local bad = {
    {"/etc/passwd", "absolute paths are not allowed"},
    {"../CMakeLists.txt", "'..' is not allowed"},
    {"paths/../../CMakeLists.txt", "'..' is not allowed"},
    {"paths/..", "'..' is not allowed"},
    {"..", "'..' is not allowed"},
    {"~/x.png", "absolute paths are not allowed"},
    {"paths\\..\\..\\x.png", "backslashes are not allowed"},
    {"", "empty file name"},
  }
  for _, case in ipairs(bad) do
    local t, err = ridgeline.load{heightmap = case[1]}
    T.eq(t, nil, case[1]); T.truthy(err:find(case[2], 1, true), ("%q: %s"):format(case[1], err))
  end
  T.raises("embedded zero in file name", ridgeline.load, {heightmap = "ramp16.png\0/../x"})
  T.truthy(ridgeline.load{heightmap = "ramp16.png"}, "a relative path inside the folder works")
  T.truthy(ridgeline.load{heightmap = "./ramp16.png"}, "./ is fine")
end)
