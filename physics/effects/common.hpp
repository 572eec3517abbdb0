#pragma once
// What the built-in effects' files share: search grids and the classes that keep a built-in's
// settings. Each file in this folder is one built-in, with its factory make_<file name>() in
// dw::physics::effects and its place in the vocabulary (physics/CMakeLists.txt makes them all).
#include <any>
#include <string>
#include <vector>

#include "core/log.hpp"
#include "core/numbers.hpp"
#include "physics/effect_types.hpp"

namespace dw::physics::effects {

inline std::vector<double> range(double a, double b, int n) {
    std::vector<double> v;
    for (int i = 0; i < n; ++i) v.push_back(a + (b - a) * i / (n - 1));
    return v;
}

// A built-in's settings: a struct of its own file's (with `enabled`), kept in Effects::settings
// under its name; an effect absent there has the struct's defaults.
template <class S>
class SettingsOf {
public:
    explicit SettingsOf(std::string name) : name_(std::move(name)) {}
    const S& operator()(const Effects& e) const {
        static const S defaults{};
        const auto it = e.settings.find(name_);
        return it == e.settings.end() ? defaults : std::any_cast<const S&>(it->second);
    }
    S& operator()(Effects& e) const {
        auto& a = e.settings[name_];
        if (!a.has_value()) a = S{};
        return std::any_cast<S&>(a);
    }
    void clear(Effects& e) const { e.settings.erase(name_); }

private:
    std::string name_;
};

// A built-in with its settings S (kept by SettingsOf).
template <class S>
class BuiltIn : public EffectType {
public:
    explicit BuiltIn(std::string name) : of(name), name_(std::move(name)) {}
    std::string name() const override { return name_; }
    void clear(Effects& e) const override { of.clear(e); }
    bool enabled(const Effects& e) const override { return of(e).enabled; }

protected:
    SettingsOf<S> of;

private:
    std::string name_;
};

// A built-in whose settings are `enabled` and one number.
template <class S>
class OneNumber : public BuiltIn<S> {
public:
    OneNumber(std::string name, double S::*value) : BuiltIn<S>(std::move(name)), value_(value) {}
    void store(Effects& e, bool on, const std::vector<double>& v, AxisPair) const override {
        auto& s = this->of(e);
        s.enabled = on;
        s.*value_ = v[0];
    }
    std::vector<double> values(const Effects& e) const override { return {this->of(e).*value_}; }

private:
    double S::*value_;
};

}  // namespace dw::physics::effects
