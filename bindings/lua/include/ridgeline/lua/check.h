// The binding's argument checks, for engines and games that bind their own types next to the
// `ridgeline` module and want the same rules and messages (docs/lua_api.md, "Conventions").
#pragma once

#include <cstddef>

struct lua_State;

namespace ridgeline::lua {

/// Every function here raises a Lua error (`bad argument #arg to 'f' (...)`) on bad input and
/// returns normally otherwise. A raised error leaves the C function through longjmp with the C
/// build of Lua (the stock interpreter) or by unwinding with the C++ build: call them before any
/// C++ object with a destructor is alive in the calling function, and read every argument into
/// plain data first.
///
/// Messages (the same everywhere in the binding):
/// - `finite number expected, got nan` (or `inf`, `-inf`); `number expected, got string` from
///   luaL_checknumber for a wrong type;
/// - `field 'speed': number expected, got string`, `field 'speed': finite number expected, got
///   nan`; option tables take numbers, not strings that look like numbers;
/// - `field 'loop': boolean expected, got number`, `field 'model': string expected, got table`;
/// - `field 'eye': array of 3 numbers expected, got table`, `field 'eye': entry 2: finite number
///   expected, got nil`;
/// - `unknown field 'colour'` for a key of an option table that the function does not know.

/// A number argument: refuses every other type, strings that look like numbers included
/// ("number expected, got string"), and NaN and infinities ("finite number expected, got nan").
double check_finite(lua_State* L, int arg);
/// Optional finite number: `def` when the argument is none or nil.
double opt_finite(lua_State* L, int arg, double def);

/// Refuses any key of the table at `arg` that is not in `names` (a null-terminated list):
/// catches typos in option tables.
void check_fields(lua_State* L, int arg, const char* const* names);
/// Number field `name` of the table at `arg` into `*out`. False (and `*out` untouched) when the
/// field is absent (nil); raises when it is not a finite number.
bool get_number_field(lua_State* L, int arg, const char* name, double* out);
/// Field `name` as an array of exactly `n` finite numbers (1 <= n <= 4) into out[0..n-1].
bool get_vector_field(lua_State* L, int arg, const char* name, int n, double* out);
/// Boolean field (true or false; nil is absent).
bool get_bool_field(lua_State* L, int arg, const char* name, bool* out);
/// String field: `*out` points into the Lua string, valid while the table holds it (copy it
/// before the table can change); `*len` (may be null) gets its length.
bool get_string_field(lua_State* L, int arg, const char* name, const char** out,
                      std::size_t* len = nullptr);

}  // namespace ridgeline::lua
