// One mechanism for every enum a scene or a file names: each enum lists its names once, next to
// its declaration, by specialising EnumNames; parseEnum and enumName read that list.
#pragma once

#include <spall/core/Error.h>

#include <string>
#include <utility>

namespace spall {

/// Specialise with `static constexpr std::pair<E, const char*> kNames[] = {...};`.
template <typename E>
struct EnumNames;

template <typename E>
std::string enumName(E value)
{
    for (const auto& [v, name] : EnumNames<E>::kNames)
        if (v == value) return name;
    failCheck("every enum value has a name (EnumNames)", __FILE__, __LINE__);
}

/// Throws InputError "'name' is unknown (expected a, b or c)".
template <typename E>
E parseEnum(const std::string& name)
{
    std::string expected;
    const size_t count = std::size(EnumNames<E>::kNames);
    for (size_t i = 0; i < count; ++i) {
        const auto& [v, known] = EnumNames<E>::kNames[i];
        if (name == known) return v;
        expected += (i == 0 ? "" : i + 1 == count ? " or " : ", ") + std::string(known);
    }
    throw InputError("'" + name + "' is unknown (expected " + expected + ")");
}

}  // namespace spall
