#pragma once
// Names looked up in one table, with one message when a name is not there:
// "unknown <what> 'x' (expected a, b or c)". An enum whose values are 0..N-1 keeps its names in
// an array in the same order, and both parses and prints through it.
#include <cstddef>
#include <iterator>
#include <optional>
#include <ranges>
#include <string>
#include <string_view>
#include <vector>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/text.hpp"

namespace dw {

// The position of `text` in `names`, or nullopt.
template <class Names>
std::optional<std::size_t> find_name(const Names& names, std::string_view text) {
    std::size_t i = 0;
    for (const auto& n : names) {
        if (std::string_view(n) == text) return i;
        ++i;
    }
    return std::nullopt;
}

// The one unknown-name message; `note` is appended inside the parentheses.
template <class Names>
std::string unknown_name_problem(std::string_view what, std::string_view text, const Names& names,
                                 std::string_view note = "") {
    std::vector<std::string> all;
    for (const auto& n : names) all.emplace_back(n);
    return log::cat("unknown ", what, " '", quote_bytes(text, kQuotedBytes), "' (expected ", choices(text, all), note,
                    ")");
}

// The enum value named `text` (its index in `names`); InputError with the known names otherwise.
template <class E, class Names>
E parse_name(const Names& names, std::string_view text, std::string_view what) {
    if (const auto i = find_name(names, text)) return static_cast<E>(*i);
    throw InputError(unknown_name_problem(what, text, names));
}

// The value of the {name, value} entry of `table` named `text` (values that are not 0..N-1);
// InputError with the known names otherwise, after "<where>: " when `where` is given (an option).
template <class Table>
auto parse_entry(const Table& table, std::string_view text, std::string_view what, std::string_view where = "") {
    for (const auto& [name, value] : table)
        if (std::string_view(name) == text) return value;
    const std::string problem = unknown_name_problem(what, text, std::views::keys(table));
    throw InputError(where.empty() ? problem : log::cat(where, ": ", problem));
}

// The name of an enum value whose names are `names` in value order.
template <class E, class Names>
std::string name_of(const Names& names, E value) {
    return std::string(*std::next(std::begin(names), static_cast<std::ptrdiff_t>(value)));
}

}  // namespace dw
