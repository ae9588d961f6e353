// Field tables: each settings struct lists its fields once — key (with the unit in its name),
// member and valid range — next to its declaration, by specialising fieldTable. That one list
// drives reading a scene, writing the resolved scene (which is also what a checkpoint stores),
// and validating values built in code, so the keys and ranges cannot drift apart.
#pragma once

#include <spall/core/EnumNames.h>
#include <spall/core/Error.h>

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

namespace spall {

/// The values a number (or each component of a vector) may take.
struct Range {
    double lo = -std::numeric_limits<double>::infinity();
    double hi = std::numeric_limits<double>::infinity();
    bool openLo = false, openHi = false;

    bool contains(double x) const
    {
        return std::isfinite(x) && (openLo ? x > lo : x >= lo) && (openHi ? x < hi : x <= hi);
    }
    /// "in (0, 100]", "at least 1", "finite".
    std::string describe() const
    {
        std::ostringstream s;
        if (std::isinf(lo) && std::isinf(hi))
            s << "finite";
        else if (std::isinf(hi))
            s << (openLo ? "above " : "at least ") << lo;
        else
            s << "in " << (openLo ? "(" : "[") << lo << ", " << hi << (openHi ? ")" : "]");
        return s.str();
    }
};

/// Ranges that come up again and again.
inline Range closed(double lo, double hi) { return Range{lo, hi, false, false}; }
inline Range aboveZeroUpTo(double hi) { return Range{0.0, hi, true, false}; }
inline Range atLeast(double lo) { return Range{lo, std::numeric_limits<double>::infinity(), false, false}; }
inline Range fraction() { return Range{0.0, 1.0, false, true}; }  ///< [0, 1)

/// An enum-valued field, read and written by its names (EnumNames).
template <typename S>
struct ChoiceMember {
    std::function<std::string(const S&)> get;
    std::function<void(S&, const std::string&)> set;  ///< throws InputError for an unknown name
};

template <typename S, typename E>
ChoiceMember<S> choice(E S::*member)
{
    return {[member](const S& s) { return enumName(s.*member); }, [member](S& s, const std::string& name) { s.*member = parseEnum<E>(name); }};
}

template <typename S>
using FieldMember = std::variant<double S::*, int S::*, int64_t S::*, uint64_t S::*, bool S::*, std::string S::*,
                                 Eigen::Vector3d S::*, ChoiceMember<S>>;

/// What a vector must be besides finite.
enum class VectorCheck { Finite, NonZero, Positive };

template <typename S>
struct Field {
    /// Where the value lives in a scene file, as a path of keys ("solver.max_time_step_s"): from
    /// the scene's root for settings a scene has once, from the element for those of a list.
    std::string key;
    FieldMember<S> member;
    Range range = {};  ///< numbers, and vectors' components
    /// The file holds scale times the member (a box's size for its half extent).
    double scale = 1.0;
    VectorCheck vectorCheck = VectorCheck::Finite;
};

/// The struct's fields. Each settings header declares its specialisation in one line,
/// `template <> const std::vector<Field<S>>& fieldTable<S>();`, defined in the stage's Settings.cpp.
template <typename S>
const std::vector<Field<S>>& fieldTable();

/// Why a number, in file units, cannot be the field's value ("must be in (0, 100], got 0"), or ""
/// when it can. Reading a scene and validating a struct built in code share it.
template <typename S>
std::string numberProblem(const Field<S>& field, double fileValue)
{
    if (field.range.contains(fileValue)) return {};
    std::ostringstream got;
    got << fileValue;
    return "must be " + field.range.describe() + ", got " + got.str();
}

/// The same for a vector, in file units.
template <typename S>
std::string vectorProblem(const Field<S>& field, const Eigen::Vector3d& fileValue)
{
    for (int i = 0; i < 3; ++i)
        if (!field.range.contains(fileValue[i])) return "every component must be " + field.range.describe();
    if (field.vectorCheck == VectorCheck::NonZero && !(fileValue.norm() > 0)) return "must not be zero";
    if (field.vectorCheck == VectorCheck::Positive && !(fileValue.minCoeff() > 0)) return "must be positive";
    return {};
}

/// Throws InputError "<context>: <key>: must be ..., got ..." for the first value out of range.
template <typename S>
void validateFields(const S& value, const std::string& context)
{
    for (const Field<S>& field : fieldTable<S>()) {
        std::string problem;
        std::visit(
            [&](const auto& member) {
                using M = std::decay_t<decltype(member)>;
                if constexpr (std::is_same_v<M, Eigen::Vector3d S::*>)
                    problem = vectorProblem(field, value.*member * field.scale);
                else if constexpr (std::is_same_v<M, double S::*> || std::is_same_v<M, int S::*> || std::is_same_v<M, int64_t S::*> ||
                                   std::is_same_v<M, uint64_t S::*>)
                    problem = numberProblem(field, static_cast<double>(value.*member) * field.scale);
            },
            field.member);
        if (!problem.empty()) throw InputError(context + ": " + field.key + ": " + problem);
    }
}

}  // namespace spall
