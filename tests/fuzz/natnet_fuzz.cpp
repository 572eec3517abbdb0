// libFuzzer target for the NatNet parsers (scripts/fuzz.sh builds it with clang, ASan and UBSan).
#include <cstddef>
#include <cstdint>
#include <span>

#include "core/errors.hpp"
#include "mocap_bridge/natnet.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    // The first byte picks the bitstream version; the rest is the payload.
    static const dw::natnet::Version versions[] = {{3, 0}, {3, 1}, {4, 0}, {4, 1}, {4, 2}, {2, 9}};
    const dw::natnet::Version v = versions[data[0] % 6];
    const std::span<const std::uint8_t> payload(data + 1, size - 1);
    try {
        dw::natnet::parse_frame(payload, v);
    } catch (const dw::InputError&) {}
    try {
        dw::natnet::parse_modeldef(payload, v);
    } catch (const dw::InputError&) {}
    try {
        dw::natnet::parse_server_info(payload);
    } catch (const dw::InputError&) {}
    try {
        dw::natnet::payload(payload);
    } catch (const dw::InputError&) {}
    return 0;
}
