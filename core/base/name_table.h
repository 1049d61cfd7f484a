#pragma once
/// \file name_table.h
/// Closed vocabularies as an enum plus one constexpr table of {value, name} rows: the names the
/// API and the logs use, looked up both ways without a switch per enum.

#include <cstddef>
#include <optional>
#include <string_view>

namespace volstyle {

template <typename E>
struct Named {
    E value;
    const char* name;
};

/// The name of `value` in `table` (the first row's name if absent: tables list every value).
template <typename E, size_t N>
constexpr const char* nameOf(const Named<E> (&table)[N], E value) {
    for (const auto& row : table)
        if (row.value == value) return row.name;
    return table[0].name;
}

template <typename E, size_t N>
constexpr std::optional<E> valueOf(const Named<E> (&table)[N], std::string_view name) {
    for (const auto& row : table)
        if (name == row.name) return row.value;
    return std::nullopt;
}

/// True when the table has one row per value 0..N-1, in order (for static_assert).
template <typename E, size_t N>
constexpr bool coversInOrder(const Named<E> (&table)[N]) {
    for (size_t i = 0; i < N; ++i)
        if (size_t(table[i].value) != i) return false;
    return true;
}

}  // namespace volstyle
