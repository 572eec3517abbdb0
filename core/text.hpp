#pragma once
// Limits on text a tool reads from a file, checked before a parser sees it, and input quoted
// safely into a one-line error (issue 43).
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace dw {

// At most this many characters of input (escapes included) are quoted in an error.
inline constexpr std::size_t kQuotedBytes = 40;
// An unknown key quoted again in its problem, after its path (up to kQuotedBytes) already names it:
// at most this many, so that a long hostile key is not said twice in full.
inline constexpr std::size_t kRepeatedKeyBytes = 16;

// `text` escaped for one line (control bytes, quotes and non-ASCII as \xHH), cut to at most n
// characters with "..." after when longer.
std::string quote_bytes(std::string_view text, std::size_t n);

// The names a message offers for a mistyped `given`: all of them ("a, b or c") when that fits in
// kChoicesChars, else up to three of the closest by edit distance within it ("a, b or c; the
// closest of 10"), so that the message stays one short line.
inline constexpr std::size_t kChoicesChars = 64;
// `last` joins the last two names (" or " for alternatives, ", " for a list).
std::string choices(std::string_view given, const std::vector<std::string>& names, std::string_view last = " or ");

// Whether `text` is well-formed UTF-8 (no overlong forms, surrogates or code points past U+10FFFF).
bool valid_utf8(std::string_view text);

// Throws dw::InputError "<what>: nests deeper than <limit> levels" when JSON (or a YAML flow
// collection) in `text` opens more than `limit` brackets or braces at once, strings skipped:
// parsers and their values recurse per level, and deep enough input ends them by stack overflow.
void require_nesting_at_most(std::string_view text, int limit, std::string_view what);

}  // namespace dw
