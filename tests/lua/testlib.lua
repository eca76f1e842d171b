-- Assertions shared by the Lua tests (runs in the sandbox: no require).
T = {}

function T.eq(got, want, what)
  if got ~= want then
    error(("%s: expected %s, got %s"):format(what or "value", tostring(want), tostring(got)), 2)
  end
end

function T.near(got, want, tol, what)
  if type(got) ~= "number" or math.abs(got - want) > tol then
    error(("%s: expected %s +- %g, got %s"):format(what or "value", tostring(want), tol,
                                                    tostring(got)), 2)
  end
end

function T.truthy(v, what)
  if not v then error((what or "condition") .. " failed", 2) end
end

-- Calls f(...) under pcall and checks that it raises an error containing `text` (plain find).
function T.raises(text, f, ...)
  local ok, err = pcall(f, ...)
  if ok then error(("expected an error containing %q, got success"):format(text), 2) end
  if not tostring(err):find(text, 1, true) then
    error(("expected an error containing %q, got %q"):format(text, tostring(err)), 2)
  end
end

-- Runs a named case; failures name it.
function T.case(name, f)
  local ok, err = pcall(f)
  if not ok then error(("case '%s': %s"):format(name, tostring(err)), 2) end
end
