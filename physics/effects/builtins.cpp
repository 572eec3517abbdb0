#include "physics/effects/builtins.hpp"

namespace dw::physics {

std::vector<std::unique_ptr<EffectType>> builtin_effects() {
    std::vector<std::unique_ptr<EffectType>> v;
#define DW_MAKE_EFFECT(name) v.push_back(effects::make_##name());
    DW_BUILTIN_EFFECTS(DW_MAKE_EFFECT)
#undef DW_MAKE_EFFECT
    return v;
}

}  // namespace dw::physics
