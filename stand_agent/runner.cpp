#include "stand_agent/runner.hpp"

#include <Eigen/Geometry>
#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>

#include "core/log.hpp"
#include "dds/time.hpp"
#include "physics/plausible.hpp"

namespace dw::stand {

PhysicsSource::PhysicsSource(dds::Participant& p, const physics::PhysicsConfig& physics, const Clock& world,
                             std::string sufferer)
    : physics_(physics),
      chain_(physics_.effects),
      live_(chain_),
      position_error_(chain_.position_error_m()),
      model_(physics),
      stand_(physics.stand),
      sufferer_name_(std::move(sufferer)),
      world_(world),
      sufferer_(0, 0, -physics.stand.height_m),
      reader_(p, dds::topics::mocap_frame, [this](const msg::MocapFrame& f, const dds::SampleMeta&) {
          {  // a frame stamped off the frames' own time (issue 70) is not felt, nor its lag counted
              std::lock_guard lock(mutex_);
              if (!stamps_.accept(dds::from_msg(f.header().stamp()))) return;
          }
          std::vector<physics::Producer> ps;
          physics::Vec3 suf = sufferer_;
          for (const auto& b : f.bodies()) {
              const physics::Vec3 pos(b.position_m().x(), b.position_m().y(), b.position_m().z());
              // A body that is no measurement (issue 70: NaN or 1e300 from a wire) is not felt.
              if (!b.tracking_valid() || !physics::plausible_position(pos)) continue;
              if (b.name() == sufferer_name_) {
                  suf = pos;
                  continue;
              }
              physics::Producer pr = model_.producer(pos - position_error_);  // reported = true + error
              const Eigen::Quaterniond q(b.orientation().w(), b.orientation().x(), b.orientation().y(),
                                         b.orientation().z());
              if (q.norm() > 0.5) pr.axis = q.normalized() * physics::Vec3::UnitZ();
              ps.push_back(pr);
          }
          std::lock_guard lock(mutex_);
          producers_ = std::move(ps);
          sufferer_ = suf;
          pose_stamp_ns_ = dds::from_msg(f.header().stamp());
      }) {}

double PhysicsSource::force(int chip, Nanos t) {
    std::lock_guard lock(mutex_);
    if (chip == 0 && pose_stamp_ns_ > 0) {  // once per conversion round: how old the poses felt are
        lag_sum_s_ += to_seconds(world_.now_ns() - (world_.monotonic_ns() - t) - pose_stamp_ns_);
        ++lag_n_;
    }
    const physics::Wrench6 read =
        live_.read(to_seconds(t), physics::to_wrench6(model_.evaluate(sufferer_, producers_)));
    return stand_.wrench_to_cells(physics::to_wrench(read))[chip];
}

std::uint64_t PhysicsSource::stray_stamps() const {
    std::lock_guard lock(mutex_);
    return stamps_.strays();
}

std::string PhysicsSource::summary() const {
    return log::cat("; ", stray_stamps(), " mocap frames refused for a stamp off the frames' time");
}

double PhysicsSource::take_air_lag_s() {
    std::lock_guard lock(mutex_);
    const double mean = lag_n_ ? lag_sum_s_ / static_cast<double>(lag_n_) : -1.0;
    lag_sum_s_ = 0, lag_n_ = 0;
    return mean;
}

double sim_clock_delay_s(const physics::PhysicsConfig& physics) {
    return physics::RecordingChain(physics.effects).clock_delay_s();
}

std::uint64_t run_agent(dds::Participant& p, Hx711Driver& driver, StandAgent& agent, const RunOptions& o) {
    if (o.realtime) {
        sched_param sp{};
        sp.sched_priority = 50;
        if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0) log::warn("SCHED_FIFO refused: ", std::strerror(errno));
        if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) log::warn("mlockall refused: ", std::strerror(errno));
    }
    dds::Writer<msg::LoadCellFrame> frames(p, dds::topics::stand_cells);
    dds::Writer<msg::WrenchStamped> wrench(p, dds::topics::stand_wrench);
    dds::Writer<msg::StandStatus> status(p, dds::topics::stand_status);
    std::atomic<bool> tare{false};
    dds::Reader<msg::ExperimentCommand> commands(p, dds::topics::experiment_command,
                                                 [&](const msg::ExperimentCommand& c, const dds::SampleMeta&) {
                                                     if (c.kind() == msg::CMD_CALIBRATE) tare = true;
                                                 });
    std::uint64_t published = 0;
    Nanos last_status = 0;
    while (!o.stop.stop_requested()) {
        if (tare.exchange(false)) {
            agent.request_tare();
            log::info("CALIBRATE: taring at hover thrust");
        }
        const Hx711Sample s = driver.read_parallel();
        StandAgent::Output out = agent.process(s);
        if (out.publish) {
            frames.write(out.frame);
            wrench.write(out.wrench);
            ++published;
        }
        const Nanos now = p.clock().monotonic_ns();
        if (out.status_changed || now - last_status > kNanosPerSecond) {
            msg::StandStatus st = agent.status();
            if (o.pipeline_delay_s) st.pipeline_delay_s(o.pipeline_delay_s());
            status.write(st);
            if (out.status_changed) {
                if (st.state() == msg::STAND_FAULT) log::error("stand: ", st.message());
                else log::info("stand: ", st.message());
            }
            last_status = now;
        }
    }
    return published;
}

}  // namespace dw::stand
