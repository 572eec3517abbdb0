#pragma once
// What the built-in effects' files share: search grids, and the
// class of an effect whose configuration is one struct in Effects with `enabled` and one number.
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

// A built-in whose configuration is one struct in Effects with `enabled` and one number.
template <class Field>
class OneNumber : public EffectType {
public:
    OneNumber(Field Effects::*field, double Field::*value) : field_(field), value_(value) {}
    void store(Effects& e, bool on, const std::vector<double>& v, AxisPair) const override {
        (e.*field_).enabled = on;
        (e.*field_).*value_ = v[0];
    }
    void clear(Effects& e) const override { e.*field_ = Field{}; }
    bool enabled(const Effects& e) const override { return (e.*field_).enabled; }
    std::vector<double> values(const Effects& e) const override { return {(e.*field_).*value_}; }

private:
    Field Effects::*field_;
    double Field::*value_;
};

// The struct of one built-in (an unnamed struct in Effects).
#define DW_FIELD(member) decltype(Effects::member)

}  // namespace dw::physics::effects
