#include "FieldIo.h"

#include <vector>

namespace spall {

using nlohmann::json;

namespace {

/// Where the parser is: an object (its keys so far, the last one) or an array (its element).
struct OpenContainer {
    bool isArray = false;
    size_t element = 0;
    std::set<std::string> keys;
    std::string key;
};

std::string pathOf(const std::vector<OpenContainer>& open)
{
    std::string path;
    for (const OpenContainer& c : open)
        path += c.isArray ? "[" + std::to_string(c.element) + "]" : (path.empty() ? "" : ".") + c.key;
    return path;
}

}  // namespace

json parseJsonStrictly(const std::string& text, const std::string& file)
{
    std::vector<OpenContainer> open;
    const auto valueDone = [&] {
        if (!open.empty() && open.back().isArray) ++open.back().element;
    };
    const json::parser_callback_t watch = [&](int, json::parse_event_t event, json& parsed) {
        switch (event) {
            case json::parse_event_t::object_start: open.push_back({}); break;
            case json::parse_event_t::array_start:
                open.emplace_back();
                open.back().isArray = true;
                break;
            case json::parse_event_t::key:
                open.back().key = parsed.get<std::string>();
                if (!open.back().keys.insert(open.back().key).second) throw InputError(file + ": " + pathOf(open) + ": the key appears twice");
                break;
            case json::parse_event_t::object_end:
            case json::parse_event_t::array_end:
                open.pop_back();
                valueDone();
                break;
            case json::parse_event_t::value: valueDone(); break;
        }
        return true;
    };
    try {
        return json::parse(text, watch);
    } catch (const json::exception& e) {
        // parse_error, and out_of_range for numbers beyond a double (found by fuzz/fuzz_scene).
        throw InputError(file + ": not valid JSON: " + e.what());
    }
}

ObjectReader::ObjectReader(const json& value, std::string file, std::string path)
    : mValue(value), mFile(std::move(file)), mPath(std::move(path))
{
    if (!mValue.is_object()) fail(mPath, "must be a JSON object");
}

void ObjectReader::fail(const std::string& key, const std::string& reason) const
{
    throw InputError(mFile + ": " + (key.empty() ? "(top level)" : key) + ": " + reason);
}

const json* ObjectReader::raw(const std::string& key)
{
    mUsed.insert(key);
    auto it = mValue.find(key);
    return it == mValue.end() ? nullptr : &*it;
}

ObjectReader* ObjectReader::child(const std::string& key)
{
    auto known = mChildren.find(key);
    if (known != mChildren.end()) return known->second.get();
    const json* v = raw(key);
    if (!v) return nullptr;
    return mChildren.emplace(key, std::make_unique<ObjectReader>(*v, mFile, keyPath(key))).first->second.get();
}

std::pair<ObjectReader*, std::string> ObjectReader::locate(const std::string& path)
{
    const size_t dot = path.find('.');
    if (dot == std::string::npos) return {this, path};
    ObjectReader* section = child(path.substr(0, dot));
    return section ? section->locate(path.substr(dot + 1)) : std::pair<ObjectReader*, std::string>{nullptr, ""};
}

std::string ObjectReader::string(const std::string& key, const std::string& fallback)
{
    const json* v = raw(key);
    if (!v) return fallback;
    if (!v->is_string()) fail(keyPath(key), "must be a string");
    return v->get<std::string>();
}

void ObjectReader::finish() const
{
    static const std::map<std::string, std::string> renamed = {
        {"checkpoint_every_frames", "output.checkpoint_every_s (wall-clock seconds between checkpoints)"},
        {"level_set_smoothing_steps", "output.fracture_smoothing_steps (smooths the fracture surface; the object's own stays as modelled)"},
        {"reflected_pressure", "loads.model (\"paper-reflected\" for true, \"paper\" for false)"}};
    for (auto it = mValue.begin(); it != mValue.end(); ++it) {
        if (mUsed.count(it.key())) continue;
        const auto r = renamed.find(it.key());
        fail(keyPath(it.key()), r == renamed.end() ? "unknown key" : "unknown key, replaced by " + r->second);
    }
    for (const auto& [key, reader] : mChildren) reader->finish();
}

}  // namespace spall
