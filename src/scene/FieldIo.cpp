#include "FieldIo.h"

namespace spall {

using nlohmann::json;

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
        {"reflected_pressure", "loads.model (\"paper-reflected\" for true, \"paper\" for false)"}};
    for (auto it = mValue.begin(); it != mValue.end(); ++it) {
        if (mUsed.count(it.key())) continue;
        const auto r = renamed.find(it.key());
        fail(keyPath(it.key()), r == renamed.end() ? "unknown key" : "unknown key, replaced by " + r->second);
    }
    for (const auto& [key, reader] : mChildren) reader->finish();
}

}  // namespace spall
