#pragma once
// The discovery part of dw-bench-security (security_discovery.cpp).
#include <chrono>
#include <string>

#include "dds/config.hpp"

namespace dw::bench {

// Rounds of six lab processes started `stagger` apart, open and secure alternating; prints the table.
void run_discovery(const dds::DdsConfig& cfg, const std::string& keys, int rounds, std::chrono::milliseconds stagger);
// One of those processes (--member ROLE): its role's endpoints, until stopped.
int run_discovery_member(const dds::DdsConfig& c, const std::string& role_name, double t0_ms);

}  // namespace dw::bench
