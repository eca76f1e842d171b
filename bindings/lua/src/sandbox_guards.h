// Sandbox guards for work that Lua's count hook cannot see: C library functions that may run for
// a long time inside one call (pattern matching, table.move/sort, load, collectgarbage), and for
// known bugs of Debian's Lua 5.4.4 that scripts can reach (coroutine.close, utf8.codes).
// Private to Ridgeline::lua; installed by host.cpp in sandboxed states only.
#pragma once

#include <lua.hpp>
#include <string_view>

namespace ridgeline::lua::detail {

/// Upper bound on the steps of one Lua 5.4 pattern match attempt (lstrlib's backtracking
/// matcher) at one start position of `subject`. A quantified single-character item (`*`, `+`,
/// `-`) can take at most r + 1 lengths, r being the longest run of subject bytes it matches, and
/// `?` two; the bound multiplies these along the pattern and adds the per-item scanning work.
/// `anchor`: a leading `^` is an anchor (find, match, gsub), not a literal (gmatch).
/// Returns +infinity for a pattern with more than 32 quantified items, and for a malformed one
/// with `*malformed` set to Lua's message for it (Lua would find it only when the matcher gets
/// there, possibly after the backtracking this guard exists to bound).
/// `scan_steps` receives the work the bound itself took (bytes x items scanned).
double pattern_steps_per_start(std::string_view subject, std::string_view pattern, bool anchor,
                               double* scan_steps, const char** malformed);

/// Replaces string.find/match/gmatch/gsub of the string library table at `string_t` (absolute
/// index; the table the string metatable indexes) with guarded versions that refuse a call whose
/// worst case exceeds the host's per-call instruction limit and charge their work to it (see
/// docs/lua_api.md, Sandbox), and removes string.dump from it.
void install_string_guards(lua_State* L, int string_t);
/// The same for table.move and table.sort of the table library at `table_t`.
void install_table_guards(lua_State* L, int table_t);
/// Bounds the nesting of coroutine.close of the coroutine library at `coroutine_t` (Lua 5.4.4
/// crashes on deep nesting: docs/reliability/sandbox.md, "Lua 5.4.4's known bugs").
void install_coroutine_guards(lua_State* L, int coroutine_t);
/// Makes utf8.codes of the utf8 library at `utf8_t` raise on stray continuation bytes, as Lua
/// 5.4.6 does (5.4.4 skips them).
void install_utf8_guards(lua_State* L, int utf8_t);

/// Charges `steps` VM-instruction equivalents to the running host call; raises
/// `instruction limit exceeded (... in <what>)` when the call's budget is spent. Defined in host.cpp.
void charge_work(lua_State* L, double steps, const char* what);
/// The per-call instruction limit of the host owning `L` (0: none). Defined in host.cpp.
double work_limit(lua_State* L);

}  // namespace ridgeline::lua::detail
