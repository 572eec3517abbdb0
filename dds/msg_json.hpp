#pragma once
// Every lab message as JSON, field names exactly as in the IDL (dds/msg_fields.hpp): for exports
// and for comparing with what independent decoders read.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <type_traits>

#include "dds/msg_fields.hpp"

namespace dw::dds {

template <class T>
nlohmann::json to_json(const T& value) {
    if constexpr (IsMessage<T>) {
        nlohmann::json j = nlohmann::json::object();
        auto put = [&j](const char* name, const auto& field) { j[name] = to_json(field); };
        fields(value, put);
        return j;
    } else if constexpr (IsSequence<T>) {
        nlohmann::json a = nlohmann::json::array();
        for (const auto& e : value) a.push_back(to_json(e));
        return a;
    } else if constexpr (std::is_enum_v<T>) {
        return static_cast<std::int64_t>(value);
    } else {
        return value;
    }
}

// Flattens nested objects and arrays into "a.b", "a[2].c" keys, in document order.
std::vector<std::pair<std::string, nlohmann::json>> flatten(const nlohmann::json& j);

}  // namespace dw::dds
