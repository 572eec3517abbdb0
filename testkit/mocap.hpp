#pragma once
// Mocap frames for tests and benchmarks: named rigid bodies at NED positions (metres), level,
// tracked.
#include <string>

#include "dw/msg/Mocap.h"

namespace dw::testkit {

inline void add_body(msg::MocapFrame& f, const std::string& name, double n, double e, double d) {
    msg::RigidBody b;
    b.name(name);
    b.position_m().x(n);
    b.position_m().y(e);
    b.position_m().z(d);
    b.orientation().w(1);
    b.tracking_valid(true);
    f.bodies().push_back(b);
}

}  // namespace dw::testkit
