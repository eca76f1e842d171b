// Guards for C library calls in the sandbox. Lua's count hook only runs between VM instructions,
// so one call of string.find with a backtracking pattern (string.find(("a"):rep(1e5),
// ".-.-.-.-b") is ~10^20 steps) or table.move over 2^50 indices never reaches it. Each guarded
// function bounds its worst case before calling the stock implementation, refuses the call when
// that bound exceeds the per-call instruction limit, and charges its work to the budget so that a
// loop of cheap-looking calls cannot multiply it.
#include "sandbox_guards.h"

#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>

namespace ridgeline::lua::detail {

namespace {

// Pattern steps per charged instruction: a matcher step costs a few ns, like a VM instruction,
// but the bound is worst case and usually far above the real work; 1/16 keeps ordinary string
// handling cheap while bounding the total at 16 times the instruction budget.
constexpr double kStepsPerInstruction = 16;
constexpr std::size_t kMaxQuantified = 32;

using uchar = unsigned char;

// A character class letter as lstrlib reads it (%a, %d, ...; upper case negates).
bool class_match(int c, int cl) {
  bool res;
  switch (std::tolower(cl)) {
    case 'a': res = std::isalpha(c) != 0; break;
    case 'c': res = std::iscntrl(c) != 0; break;
    case 'd': res = std::isdigit(c) != 0; break;
    case 'g': res = std::isgraph(c) != 0; break;
    case 'l': res = std::islower(c) != 0; break;
    case 'p': res = std::ispunct(c) != 0; break;
    case 's': res = std::isspace(c) != 0; break;
    case 'u': res = std::isupper(c) != 0; break;
    case 'w': res = std::isalnum(c) != 0; break;
    case 'x': res = std::isxdigit(c) != 0; break;
    default: return cl == c;
  }
  return std::isupper(cl) != 0 ? !res : res;
}

// [set]: p at '[', close at the closing ']'.
bool set_match(int c, const char* p, const char* close) {
  bool sig = true;
  if (p[1] == '^') {
    sig = false;
    ++p;
  }
  while (++p < close) {
    if (*p == '%') {
      ++p;
      if (class_match(c, uchar(*p))) return sig;
    } else if (p[1] == '-' && p + 2 < close) {
      p += 2;
      if (uchar(p[-2]) <= c && c <= uchar(*p)) return sig;
    } else if (uchar(*p) == c) {
      return sig;
    }
  }
  return !sig;
}

bool item_match(int c, const char* p, const char* ep) {
  switch (*p) {
    case '.': return true;
    case '%': return class_match(c, uchar(p[1]));
    case '[': return set_match(c, p, ep - 1);
    default: return uchar(*p) == c;
  }
}

// End of the single-character item at p, or nullptr when malformed.
const char* item_end(const char* p, const char* end) {
  if (p >= end) return nullptr;
  const char c = *p++;
  if (c == '%') return p < end ? p + 1 : nullptr;
  if (c == '[') {
    if (p < end && *p == '^') ++p;
    for (;;) {  // the first character of the set may be ']'
      if (p >= end) return nullptr;
      if (*p++ == '%' && p < end) ++p;
      if (p < end && *p == ']') return p + 1;
    }
  }
  return p;
}

struct Quantified {
  const char* p;
  const char* ep;
  char q;
};

}  // namespace

double pattern_steps_per_start(std::string_view subject, std::string_view pattern, bool anchor,
                               double* scan_steps, const char** malformed) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  *scan_steps = 0;
  *malformed = nullptr;
  const auto bad = [&](const char* why) {
    *malformed = why;
    return kInf;
  };
  const double n = static_cast<double>(subject.size());
  const char* p = pattern.data();
  const char* const end = p + pattern.size();
  if (anchor && p < end && *p == '^') ++p;
  std::array<Quantified, kMaxQuantified> items{};
  std::size_t count = 0;
  double linear = 1;  // steps of the deterministic items, paid at every leaf of the search
  while (p < end) {
    switch (*p) {
      case '(':
        p += (p + 1 < end && p[1] == ')') ? 2 : 1;
        linear += 1;
        continue;
      case ')':
        ++p;
        linear += 1;
        continue;
      case '$':
        if (p + 1 == end) {
          ++p;
          continue;
        }
        break;
      case '%':
        if (p + 1 < end && p[1] == 'b') {  // %bxy scans up to the end of the subject
          if (p + 3 >= end) return bad("missing arguments to '%b'");
          p += 4;
          linear += n + 1;
          continue;
        }
        if (p + 1 < end && p[1] == 'f') {
          p += 2;
          if (p >= end || *p != '[') return bad("missing '[' after '%f' in pattern");
          const char* e = item_end(p, end);
          if (e == nullptr) return bad("malformed pattern (missing ']')");
          linear += static_cast<double>(e - p);
          p = e;
          continue;
        }
        if (p + 1 < end && std::isdigit(uchar(p[1])) != 0) {  // back reference: compares a capture
          p += 2;
          linear += n + 1;
          continue;
        }
        break;
      default: break;
    }
    const char* ep = item_end(p, end);
    if (ep == nullptr)
      return bad(*p == '%' ? "malformed pattern (ends with '%')" : "malformed pattern (missing ']')");
    const char q = ep < end ? *ep : '\0';
    if (q == '?' || q == '*' || q == '+' || q == '-') {
      if (count == kMaxQuantified) return kInf;
      items[count++] = {p, ep, q};
      p = ep + 1;
    } else {
      linear += static_cast<double>(ep - p);
      p = ep;
    }
  }
  // Longest run of subject bytes each quantified item matches (one pass per item with a
  // 256-entry table).
  double total = linear;  // built from the last item backwards: T_i = e_i + b_i * T_{i+1}
  for (std::size_t k = count; k-- > 0;) {
    const Quantified& it = items[k];
    const double len = static_cast<double>(it.ep - it.p);
    if (it.q == '?') {
      total = len + 2 * total;
      continue;
    }
    std::array<bool, 256> in{};
    for (int c = 0; c < 256; ++c) in[c] = item_match(c, it.p, it.ep);
    std::size_t run = 0, best = 0;
    for (const char ch : subject) {
      run = in[uchar(ch)] ? run + 1 : 0;
      best = std::max(best, run);
    }
    *scan_steps += n + 256 * len;
    const double r = static_cast<double>(best);
    total = (r + 1) * len + (r + 1) * total;  // expansion counted once, then every length tried
  }
  return total;
}

namespace {

enum class Kind { kFind, kMatch, kGmatch, kGsub };
constexpr const char* kNames[] = {"string.find", "string.match", "string.gmatch", "string.gsub"};

// lstrlib's "no special characters" test for find's plain search.
bool no_specials(std::string_view p) {
  for (const char c : p)
    if (std::string_view("^$*+?.([%-").find(c) != std::string_view::npos) return false;
  return true;
}

// Wrapper for find/match/gmatch/gsub: upvalue 1 the stock function, upvalue 2 the kind.
int guarded_pattern(lua_State* L) {
  const auto kind = static_cast<Kind>(lua_tointeger(L, lua_upvalueindex(2)));
  const char* what = kNames[static_cast<int>(kind)];
  const int nargs = lua_gettop(L);
  const auto convertible = [L](int i) {
    return lua_type(L, i) == LUA_TSTRING || lua_type(L, i) == LUA_TNUMBER;
  };
  const double cap = work_limit(L);
  double worst = 0, per_start = 0, init = 1, n = 0;
  if (cap > 0 && nargs >= 2 && convertible(1) && convertible(2)) {
    std::size_t ls = 0, lp = 0;
    const char* s = lua_tolstring(L, 1, &ls);
    const char* p = lua_tolstring(L, 2, &lp);
    n = static_cast<double>(ls);
    int iok = 0;
    const lua_Integer i = lua_tointegerx(L, 3, &iok);
    if (kind != Kind::kGsub && iok != 0) {  // as lstrlib's posrelatI
      if (i > 0)
        init = static_cast<double>(i);
      else if (i < -static_cast<lua_Integer>(ls))
        init = 1;
      else if (i < 0)
        init = n + static_cast<double>(i) + 1;
    }
    const std::string_view subject(s, ls), pattern(p, lp);
    double scan = 0;
    const char* malformed = nullptr;
    const bool plain = kind == Kind::kFind && (lua_toboolean(L, 4) || no_specials(pattern));
    if (plain)
      per_start = static_cast<double>(lp) + 1;
    else
      per_start =
          pattern_steps_per_start(subject, pattern, kind != Kind::kGmatch, &scan, &malformed);
    if (malformed != nullptr) return luaL_error(L, "%s: %s", what, malformed);
    const bool anchored = !plain && kind != Kind::kGmatch && lp > 0 && p[0] == '^';
    const double starts = anchored ? 1 : std::max(0.0, n - init + 2);
    worst = starts * per_start;
    // The bound's own scan is charged first, so that refused calls in a pcall loop cost too.
    charge_work(L, scan / 4, what);
    if (worst > cap) {
      if (std::isinf(per_start))
        return luaL_error(L, "%s: pattern too complex for the sandbox (more than %d quantified items)",
                          what, static_cast<int>(kMaxQuantified));
      char msg[256];
      std::snprintf(msg, sizeof msg,
                    "%s: pattern too costly for the sandbox: up to %.3g matcher steps on a "
                    "%zu-byte subject, limit %.3g per call (split the subject or simplify the "
                    "pattern)",
                    what, worst, ls, cap);
      return luaL_error(L, "%s", msg);
    }
  }
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_insert(L, 1);
  lua_call(L, nargs, LUA_MULTRET);
  const int nres = lua_gettop(L);
  if (worst > 0) {
    double work = worst;
    // find stops at its first match: only the start positions before it were tried.
    if (kind == Kind::kFind && nres >= 1 && lua_type(L, 1) == LUA_TNUMBER)
      work = std::max(1.0, static_cast<double>(lua_tointeger(L, 1)) - init + 1) * per_start;
    // gsub builds its result piece by piece: ~16 instructions' worth per substitution.
    const double pieces = kind == Kind::kGsub && nres >= 2 && lua_type(L, 2) == LUA_TNUMBER
                              ? 16 * lua_tonumber(L, 2)
                              : 0;
    charge_work(L, work / kStepsPerInstruction + pieces, what);
  }
  return nres;
}

// string.rep(s, n [, sep]): lstrlib copies s once per repetition (a memcpy call each: ~1 ns per
// repetition), far more than the allocation charge of one instruction per 64 bytes for a short s.
int guarded_rep(lua_State* L) {
  int ok = 0;
  const lua_Integer n = lua_tointegerx(L, 2, &ok);
  const double reps = ok != 0 && n > 0 ? static_cast<double>(n) : 0;
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_insert(L, 1);
  lua_call(L, lua_gettop(L) - 1, LUA_MULTRET);
  // Charged once built: a result over the memory cap is refused by the allocator before any
  // copying, and one that fits is at most a few tens of milliseconds of copying.
  if (work_limit(L) > 0 && reps > 0 && lua_type(L, 1) == LUA_TSTRING)
    charge_work(L, reps + static_cast<double>(lua_rawlen(L, 1)) / 16, "string.rep");
  return lua_gettop(L);
}

// table.move(a1, f, e, t [, a2]): one get and one set per element, all in C.
int guarded_move(lua_State* L) {
  const double cap = work_limit(L);
  int fok = 0, eok = 0;
  // As luaL_checkinteger reads them: floats with an integral value and numeric strings count.
  const lua_Integer f = lua_tointegerx(L, 2, &fok), e = lua_tointegerx(L, 3, &eok);
  if (cap > 0 && fok != 0 && eok != 0) {
    if (e >= f) {
      const double count = static_cast<double>(e) - static_cast<double>(f) + 1;
      if (count > cap) {
        char msg[128];
        std::snprintf(msg, sizeof msg,
                      "table.move: %.3g elements is more than the sandbox allows per call", count);
        return luaL_error(L, "%s", msg);
      }
      charge_work(L, count, "table.move");
    }
  }
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_insert(L, 1);
  lua_call(L, lua_gettop(L) - 1, LUA_MULTRET);
  return lua_gettop(L);
}

// table.sort(t [, comp]): n log2 n comparisons in C (a Lua comparator is counted by the hook too).
int guarded_sort(lua_State* L) {
  if (work_limit(L) > 0 && lua_type(L, 1) == LUA_TTABLE) {
    const double n = static_cast<double>(lua_rawlen(L, 1));
    if (n > 1) charge_work(L, n * std::log2(n), "table.sort");
  }
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_insert(L, 1);
  lua_call(L, lua_gettop(L) - 1, LUA_MULTRET);
  return lua_gettop(L);
}

// coroutine.close(co) with its nesting bounded (Lua 5.4.4 bug 9 on lua.org/bugs.html,
// "C-stack overflow with deep nesting of coroutine.close"): closing a coroutine runs its pending
// __close handlers on the coroutine's own C-call count, so a __close that closes another
// coroutine, whose __close closes another... recurses in C without limit and crashes the
// process (30,000 levels did with an 8 MiB stack). Lua 5.4.6 counts the closing against the
// caller's C calls; the C API of 5.4.4 cannot, so the sandbox bounds the nesting instead. The
// depth lives in a userdata upvalue (2); the original call runs under lua_pcall so that the depth
// is restored whatever it raises.
constexpr int kMaxCloseNesting = 8;

int guarded_coroutine_close(lua_State* L) {
  int* depth = static_cast<int*>(lua_touserdata(L, lua_upvalueindex(2)));
  if (*depth >= kMaxCloseNesting)
    return luaL_error(L, "C stack overflow (coroutine.close nested more than %d deep)",
                      kMaxCloseNesting);
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_insert(L, 1);
  ++*depth;
  const int rc = lua_pcall(L, lua_gettop(L) - 1, LUA_MULTRET, 0);
  --*depth;
  if (rc != LUA_OK) return lua_error(L);
  return lua_gettop(L);
}

// utf8.codes(s [, lax]) raising on stray continuation bytes (Lua 5.4.4 bug 8, "'utf8.codes' does
// not raise an error on spurious continuation bytes": 5.4.4's iterator skips them silently, so
// "a\x80" iterates as "a"). As Lua 5.4.6 does: the string may not start with one, and none may
// follow a decoded character. The iterator (upvalue 1: the stock one) is wrapped.
bool is_continuation(const char* s, std::size_t len, std::size_t at) {
  return at < len && (static_cast<uchar>(s[at]) & 0xC0) == 0x80;
}

int guarded_utf8_iterator(lua_State* L) {
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_pushvalue(L, 1);
  lua_pushvalue(L, 2);
  lua_call(L, 2, 2);
  if (lua_isnil(L, -2)) return 0;
  std::size_t len = 0;
  const char* s = lua_tolstring(L, 1, &len);
  const lua_Integer pos = lua_tointeger(L, -2);
  const lua_Integer code = lua_tointeger(L, -1);
  // Bytes of the character just decoded (Lua refuses overlong encodings, so the code point
  // fixes the length).
  const int bytes = code < 0x80        ? 1
                    : code < 0x800     ? 2
                    : code < 0x10000   ? 3
                    : code < 0x200000  ? 4
                    : code < 0x4000000 ? 5
                                       : 6;
  if (s != nullptr && pos >= 1 && is_continuation(s, len, std::size_t(pos - 1 + bytes)))
    return luaL_error(L, "invalid UTF-8 code");
  return 2;
}

int guarded_utf8_codes(lua_State* L) {
  std::size_t len = 0;
  const char* s = luaL_checklstring(L, 1, &len);
  luaL_argcheck(L, !is_continuation(s, len, 0), 1, "invalid UTF-8 code");
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_insert(L, 1);
  lua_call(L, lua_gettop(L) - 1, 3);
  lua_pushvalue(L, -3);
  lua_pushcclosure(L, guarded_utf8_iterator, 1);
  lua_replace(L, -4);
  return 3;
}

}  // namespace

void install_string_guards(lua_State* L, int string_t) {
  static const char* const kFns[] = {"find", "match", "gmatch", "gsub"};
  for (int k = 0; k < 4; ++k) {
    lua_getfield(L, string_t, kFns[k]);
    lua_pushinteger(L, k);
    lua_pushcclosure(L, guarded_pattern, 2);
    lua_setfield(L, string_t, kFns[k]);
  }
  lua_getfield(L, string_t, "rep");
  lua_pushcclosure(L, guarded_rep, 1);
  lua_setfield(L, string_t, "rep");
  lua_pushnil(L);
  lua_setfield(L, string_t, "dump");
}

void install_table_guards(lua_State* L, int table_t) {
  lua_getfield(L, table_t, "move");
  lua_pushcclosure(L, guarded_move, 1);
  lua_setfield(L, table_t, "move");
  lua_getfield(L, table_t, "sort");
  lua_pushcclosure(L, guarded_sort, 1);
  lua_setfield(L, table_t, "sort");
}

void install_coroutine_guards(lua_State* L, int coroutine_t) {
  lua_getfield(L, coroutine_t, "close");
  *static_cast<int*>(lua_newuserdatauv(L, sizeof(int), 0)) = 0;
  lua_pushcclosure(L, guarded_coroutine_close, 2);
  lua_setfield(L, coroutine_t, "close");
}

void install_utf8_guards(lua_State* L, int utf8_t) {
  lua_getfield(L, utf8_t, "codes");
  lua_pushcclosure(L, guarded_utf8_codes, 1);
  lua_setfield(L, utf8_t, "codes");
}

}  // namespace ridgeline::lua::detail
