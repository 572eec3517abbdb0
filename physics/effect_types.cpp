#include "physics/effect_types.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <stdexcept>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/names.hpp"

namespace dw::physics {

namespace {

// Built once, thread-safely (a function's static); registrations come at start-up only.
struct Registry {
    std::vector<std::unique_ptr<EffectType>> owned;
    std::vector<const EffectType*> views;
    void add(std::unique_ptr<EffectType> t) {
        views.push_back(t.get());
        owned.push_back(std::move(t));
    }
};

Registry& registry() {
    static Registry r = [] {
        Registry built;
        for (auto& t : builtin_effects()) built.add(std::move(t));
        return built;
    }();
    return r;
}

// Each module of kEffectModulesVariable loaded, kept for the process's life; its static
// registrations add its effects to the registry as it loads.
void load_effect_modules() {
    const char* list = std::getenv(kEffectModulesVariable);
    if (!list) return;
    std::string_view rest(list);
    while (!rest.empty()) {
        const auto colon = rest.find(':');
        const std::string path(rest.substr(0, colon));
        rest = colon == std::string_view::npos ? std::string_view{} : rest.substr(colon + 1);
        if (path.empty()) continue;
        if (!::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL))
            throw InputError(log::cat(kEffectModulesVariable, ": cannot load effect module: ", ::dlerror()));
    }
}

}  // namespace

const std::vector<const EffectType*>& effect_types() {
    static const bool loaded = (load_effect_modules(), true);  // once; a failure is thrown again next time
    (void)loaded;
    return registry().views;
}

namespace {
std::vector<std::string> names() {
    std::vector<std::string> out;
    for (const auto* t : effect_types()) out.push_back(t->name());
    return out;
}
}  // namespace

std::string effect_names() { return log::alternatives(names()); }

const EffectType& clock_effect() {
    for (const auto* t : effect_types())
        if (t->stage() == Stage::clock) return *t;
    throw std::logic_error("no effect acts on the stamps' clock");
}

const EffectType& effect_type(const std::string& name, const std::string& what) {
    const auto known = names();
    const auto i = find_name(known, name);
    if (!i) throw InputError(log::cat(what, ": ", unknown_name_problem("effect", name, known)));
    return *effect_types()[*i];
}

void register_effect(std::unique_ptr<EffectType> type) {
    for (const auto* t : registry().views)  // not effect_types(): a module registers while it loads
        if (t->name() == type->name()) throw std::logic_error("effect registered twice: " + type->name());
    registry().add(std::move(type));
}

bool EffectType::applies(int neighbours, bool flying) const {
    (void)neighbours;
    (void)flying;
    return true;
}

std::vector<double> EffectType::neutral() const {
    std::vector<double> v;
    for (const auto& p : parameters()) v.push_back(p.start);
    return v;
}

void EffectType::set(Effects& e, const std::vector<double>& values, AxisPair axes) const {
    store(e, true, values, axes);
}
void EffectType::store(Effects& e, bool on, const std::vector<double>& values, AxisPair) const {
    if (on) e.extra[name()] = values;
    else e.extra.erase(name());
}
void EffectType::clear(Effects& e) const { e.extra.erase(name()); }
bool EffectType::enabled(const Effects& e) const { return e.extra.count(name()) > 0; }
std::vector<double> EffectType::values(const Effects& e) const {
    auto it = e.extra.find(name());
    return it == e.extra.end() ? neutral() : it->second;
}

void EffectType::keys(KeyVisitor& k, Effects& e) const {
    bool on = enabled(e);
    k.flag("enabled", on);
    std::vector<double> v = values(e);
    const auto params = parameters();
    for (std::size_t i = 0; i < params.size(); ++i)
        k.number(params[i].name, v[i], {params[i].config_min, params[i].config_max});
    store(e, on, v, {});
}

void EffectType::on_recording(const std::vector<double>&, const std::vector<double>&, RecordedWrench&) const {}
void EffectType::sensor_step(const Effects&, double, const Wrench6&, const Wrench6& x1, Wrench6& y) const { y = x1; }
void EffectType::on_calibration(const Effects&, Wrench6&, const Wrench6&) const {}

}  // namespace dw::physics
