#pragma once
// How the planner's setpoints reach the vehicles, behind one interface: `sim` (the lab's
// vehicles/setpoint topic, which the simulated vehicles follow) and `px4` (PX4 through its
// uXRCE-DDS bridge: swarm_planner/px4_link.hpp).
#include <array>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "dds/endpoint.hpp"
#include "physics/vehicle.hpp"
#include "swarm_planner/plan.hpp"
#include "swarm_planner/px4_config.hpp"

namespace dw::planner {

// Where arming stands, asked at the setpoint rate while the vehicles hold on the ground.
struct ArmProgress {
    enum class State { pending, ready, refused };
    State state = State::pending;
    std::string reason;  // refused: why, in one line
};

// Every link sends through one last gate (issue 70): whatever the planner computed, a setpoint that
// is not finite or lies outside the geofence never reaches a vehicle. That vehicle gets instead
// the last setpoint of its own that passed, at rest (no velocity, no acceleration), or nothing at
// all if none has passed yet; each vehicle's first refusal is said as an error line.
//
// From begin_descent() on — every abort, every landing — the gate lets each vehicle only go down
// (issue 69): no setpoint's D is above where the vehicle is, as the link itself knows it in the
// frame it commands in (down_of: PX4's own estimate for PX4, whatever the lab's frames say), nor
// above the D last delivered to it; a velocity or acceleration that points up is dropped. Below
// the floor is allowed then: that is where a landing ends.
class VehicleLink {
public:
    virtual ~VehicleLink() = default;
    void send(const std::vector<physics::Setpoint>& sps, Nanos now_ns);
    void begin_descent() { descending_ = true; }
    bool descending() const { return descending_; }
    void set_fence(const Geofence& fence) { fence_ = fence; }  // default: the default room
    std::uint64_t refused() const { return refused_; }         // setpoints the gate stopped
    // Advances arming (mode, arm, confirmation, retries); the setpoint stream goes on meanwhile.
    virtual ArmProgress arm() { return {ArmProgress::State::ready, ""}; }
    // In flight: why the vehicles no longer follow this link (a PX4 failsafe), if so.
    virtual std::optional<std::string> failsafe() { return std::nullopt; }
    // Whether vehicle i (the plan's order) flies under position control, so that the tracking bound
    // applies: PX4 climbs vertically on a ramp after its motors spool up, and only then follows its
    // setpoints. `how` says where it is otherwise ("on the ground", "in its take-off ramp").
    virtual bool following(std::size_t i, std::string& how) {
        (void)i, (void)how;
        return true;
    }
    virtual void land() {}  // after the landing setpoints
    // After land(): the vehicles not yet confirmed landed ("v1 (armed, AUTO_LAND)"), nullopt when
    // every one is (PX4: disarmed). A link that cannot tell confirms at once.
    virtual std::optional<std::string> still_flying() { return std::nullopt; }
    // How long a landing may take to be confirmed.
    virtual double land_timeout_s() const { return 0; }

protected:
    // Each vehicle's setpoint after the gate; nothing for a vehicle none of whose setpoints passed.
    virtual void deliver(const std::vector<std::optional<physics::Setpoint>>& sps, Nanos now_ns) = 0;
    // Where vehicle i (the plan's order) is, down (NED D in the lab's frame, as this link knows it
    // through the frame it commands in); nullopt when it does not know it (now).
    virtual std::optional<double> down_of(std::size_t i) = 0;

private:
    // Whether sp may pass: finite and inside the fence (in descent, the floor not counted).
    bool admissible(const physics::Setpoint& sp) const;
    // In descent: sp no higher than vehicle i is or was last sent, and nothing pointing up.
    physics::Setpoint only_down(std::size_t i, physics::Setpoint sp);

    Geofence fence_;
    std::vector<std::optional<physics::Setpoint>> passed_;  // per vehicle: the last that passed
    std::vector<std::optional<double>> delivered_d_;        // per vehicle: the D last delivered
    std::vector<bool> said_;
    std::uint64_t refused_ = 0;
    bool descending_ = false;
};

enum class LinkKind { sim, px4 };
inline constexpr const char* kLinkNames[] = {"sim", "px4"};  // LinkKind's values in order
// "px4" -> LinkKind::px4; anything else: InputError naming `option` and the known names.
LinkKind parse_link(std::string_view name, std::string_view option);

// What the lab commands, on vehicles/setpoint in the lab's frame: the simulated vehicles follow
// it, and with any link it is the record of what was sent (the recorder keeps it).
class SetpointWriter {
public:
    SetpointWriter(dds::Participant& p, std::vector<std::string> vehicles, std::string run_id);
    void write(const std::vector<std::optional<physics::Setpoint>>& gated, Nanos now_ns);

private:
    std::vector<std::string> vehicles_;
    std::string run_id_;
    dds::Writer<msg::VehicleSetpoint> writer_;
};

// Each of the plan's vehicles' latest tracked D from vehicles/state (the lab's frame), while fresh.
class VehicleHeights {
public:
    VehicleHeights(dds::Participant& p, const std::vector<std::string>& vehicles);
    std::optional<double> down_of(std::size_t i) const;

private:
    dds::Participant& p_;
    std::vector<std::string> vehicles_;
    mutable std::mutex mutex_;
    std::map<std::string, std::pair<double, Nanos>> latest_;  // D, when (monotonic)
    dds::Reader<msg::VehicleState> reader_;
};
// How old a vehicle's position may be and still say where it is (for the descent's gate).
inline constexpr double kPositionFreshS = 0.5;

// The simulated vehicles: the setpoints on vehicles/setpoint, where they are from vehicles/state.
class SimLink final : public VehicleLink {
public:
    SimLink(dds::Participant& p, std::vector<std::string> vehicles, std::string run_id);

private:
    void deliver(const std::vector<std::optional<physics::Setpoint>>& sps, Nanos now_ns) override;
    std::optional<double> down_of(std::size_t i) override { return heights_.down_of(i); }
    SetpointWriter writer_;
    VehicleHeights heights_;
};

// The link of that kind for the plan's vehicles (`px4`: with these PX4 settings).
std::unique_ptr<VehicleLink> make_link(LinkKind kind, dds::Participant& p, const std::vector<std::string>& vehicles,
                                       const std::string& run_id, const Px4Options& px4);

}  // namespace dw::planner
