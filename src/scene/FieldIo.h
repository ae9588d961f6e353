// Reading and writing settings structs as JSON through their field tables (core/Fields.h).
#pragma once

#include <spall/core/Error.h>
#include <spall/core/Fields.h>

#include <nlohmann/json.hpp>

#include <limits>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>

namespace spall {

/// JSON text as a value; throws InputError naming `file` when it is not JSON, or when an object
/// holds a key twice (JSON leaves that undefined, and the parser would keep the last silently),
/// naming the key's path as ObjectReader does.
nlohmann::json parseJsonStrictly(const std::string& text, const std::string& file);

/// Reads one JSON object strictly: every key must be read, types must match, values must pass
/// their checks; errors name the file, the key path and the reason. Nested objects get readers
/// of their own, which finish() checks with their parent.
class ObjectReader {
public:
    ObjectReader(const nlohmann::json& value, std::string file, std::string path);

    [[noreturn]] void fail(const std::string& key, const std::string& reason) const;
    std::string keyPath(const std::string& key) const { return mPath.empty() ? key : mPath + "." + key; }
    const std::string& file() const { return mFile; }
    bool has(const std::string& key) const { return mValue.contains(key); }

    /// The value at `key`, marked as read; null when absent.
    const nlohmann::json* raw(const std::string& key);
    /// The reader of the nested object at `key` (kept until finish()); null when absent.
    ObjectReader* child(const std::string& key);
    /// The reader holding the last key of a dotted path, and that key; null when a section of
    /// the path is absent.
    std::pair<ObjectReader*, std::string> locate(const std::string& keyPath);

    std::string string(const std::string& key, const std::string& fallback);
    /// Calls parse(reader, index) for each element of the array at `key`, if present.
    template <typename F>
    void array(const std::string& key, F&& parse)
    {
        const nlohmann::json* v = raw(key);
        if (!v) return;
        if (!v->is_array()) fail(keyPath(key), "must be an array");
        for (size_t i = 0; i < v->size(); ++i) {
            ObjectReader element((*v)[i], mFile, keyPath(key) + "[" + std::to_string(i) + "]");
            parse(element, i);
            element.finish();
        }
    }
    /// Turns a library InputError about a value into one naming this key.
    template <typename F>
    auto checked(const std::string& key, F&& f) -> decltype(f())
    {
        try {
            return f();
        } catch (const InputError& e) {
            fail(keyPath(key), e.what());
        }
    }
    /// Every key of this object (and its children) that was not read is unknown; a renamed key
    /// says what replaced it.
    void finish() const;

private:
    const nlohmann::json& mValue;
    std::string mFile;
    std::string mPath;
    std::set<std::string> mUsed;
    std::map<std::string, std::unique_ptr<ObjectReader>> mChildren;
};

/// One field's value from JSON into the struct, checked against the field's type and range.
template <typename S>
void readField(ObjectReader& reader, const std::string& key, const nlohmann::json& v, const Field<S>& field, S& value)
{
    auto fail = [&](const std::string& reason) { reader.fail(reader.keyPath(key), reason); };
    auto check = [&](const std::string& problem) {
        if (!problem.empty()) fail(problem);
    };
    std::visit(
        [&](const auto& member) {
            using M = std::decay_t<decltype(member)>;
            if constexpr (std::is_same_v<M, double S::*>) {
                if (!v.is_number()) fail("must be a number, got " + std::string(v.type_name()));
                check(numberProblem(field, v.get<double>()));
                value.*member = v.get<double>() / field.scale;
            } else if constexpr (std::is_same_v<M, int S::*> || std::is_same_v<M, int64_t S::*> || std::is_same_v<M, uint64_t S::*>) {
                using Int = std::decay_t<decltype(value.*member)>;
                if (!v.is_number_integer()) fail("must be an integer");
                // A uint64 above INT64_MAX reads back negative here and fails the type's range.
                const int64_t x = v.get<int64_t>();
                if (x < static_cast<int64_t>(std::numeric_limits<Int>::min()) ||
                    static_cast<uint64_t>(x) > static_cast<uint64_t>(std::numeric_limits<Int>::max()))
                    fail("must be an integer that fits in " + std::to_string(sizeof(Int) * 8) + " bits" +
                         (std::is_signed_v<Int> ? "" : ", not negative"));
                check(numberProblem(field, static_cast<double>(x)));
                value.*member = static_cast<Int>(x);
            } else if constexpr (std::is_same_v<M, bool S::*>) {
                if (!v.is_boolean()) fail("must be true or false");
                value.*member = v.get<bool>();
            } else if constexpr (std::is_same_v<M, std::string S::*>) {
                if (!v.is_string()) fail("must be a string");
                value.*member = v.get<std::string>();
            } else if constexpr (std::is_same_v<M, Eigen::Vector3d S::*>) {
                if (!v.is_array() || v.size() != 3) fail("must be an array of 3 numbers");
                Eigen::Vector3d x;
                for (int i = 0; i < 3; ++i) {
                    if (!v[i].is_number() || !std::isfinite(v[i].get<double>())) fail("must be an array of 3 finite numbers");
                    x[i] = v[i].get<double>();
                }
                check(vectorProblem(field, x));
                value.*member = x / field.scale;
            } else {
                if (!v.is_string()) fail("must be a string");
                reader.checked(key, [&] { member.set(value, v.get<std::string>()); });
            }
        },
        field.member);
}

/// Every field of the struct's table that the JSON holds (the others keep their values).
template <typename S>
void readFields(ObjectReader& reader, S& value)
{
    for (const Field<S>& field : fieldTable<S>()) {
        auto [holder, key] = reader.locate(field.key);
        if (!holder) continue;
        if (const nlohmann::json* v = holder->raw(key)) readField(*holder, key, *v, field, value);
    }
}

/// Every field of the struct's table into `out`, nested objects made as the key paths say.
template <typename S>
void writeFields(const S& value, nlohmann::json& out)
{
    for (const Field<S>& field : fieldTable<S>()) {
        std::string pointer = "/" + field.key;
        for (char& c : pointer)
            if (c == '.') c = '/';
        nlohmann::json& slot = out[nlohmann::json::json_pointer(pointer)];
        std::visit(
            [&](const auto& member) {
                using M = std::decay_t<decltype(member)>;
                if constexpr (std::is_same_v<M, double S::*>) {
                    slot = value.*member * field.scale;
                } else if constexpr (std::is_same_v<M, Eigen::Vector3d S::*>) {
                    const Eigen::Vector3d x = value.*member * field.scale;
                    slot = nlohmann::json::array({x.x(), x.y(), x.z()});
                } else if constexpr (std::is_same_v<M, ChoiceMember<S>>) {
                    slot = member.get(value);
                } else {
                    slot = value.*member;
                }
            },
            field.member);
    }
}

}  // namespace spall
