// Field tables: each settings struct lists its fields once — key (with the unit in its name),
// member and valid range — next to its declaration, by specialising FieldTable. That one list
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

/// Specialise for each settings struct: `static const std::vector<Field<S>>& fields();`, defined
/// in the stage's Settings.cpp.
template <typename S>
struct FieldTable;

/// Throws InputError "<context>: <key>: must be ..., got ..." for the first value out of range.
template <typename S>
void validateFields(const S& value, const std::string& context)
{
    for (const Field<S>& field : FieldTable<S>::fields()) {
        auto fail = [&](const std::string& reason) { throw InputError(context + ": " + field.key + ": " + reason); };
        std::visit(
            [&](const auto& member) {
                using M = std::decay_t<decltype(member)>;
                if constexpr (std::is_same_v<M, Eigen::Vector3d S::*>) {
                    const Eigen::Vector3d& v = value.*member;
                    for (int i = 0; i < 3; ++i)
                        if (!field.range.contains(v[i] * field.scale)) fail("every component must be " + field.range.describe());
                    if (field.vectorCheck == VectorCheck::NonZero && !(v.norm() > 0)) fail("must not be zero");
                    if (field.vectorCheck == VectorCheck::Positive && !(v.minCoeff() > 0)) fail("must be positive");
                } else if constexpr (std::is_same_v<M, double S::*> || std::is_same_v<M, int S::*> || std::is_same_v<M, int64_t S::*> ||
                                     std::is_same_v<M, uint64_t S::*>) {
                    const double x = static_cast<double>(value.*member) * field.scale;
                    if (!field.range.contains(x)) {
                        std::ostringstream got;
                        got << value.*member;
                        fail("must be " + field.range.describe() + ", got " + got.str());
                    }
                }
            },
            field.member);
    }
}

}  // namespace spall
