// The PX4 vehicle link: a subscriber built from the px4_msgs definitions, with PX4's own QoS for
// its fmu/in topics (BEST_EFFORT, VOLATILE, KEEP_LAST), receives the planner's setpoints on the
// right topic names and type names, with the right values in PX4's local frame.
#include <gtest/gtest.h>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <cmath>
#include <mutex>
#include <thread>

#include "swarm_planner/vehicle_link.hpp"
#include "support.hpp"

namespace fdds = eprosima::fastdds::dds;
using namespace std::chrono_literals;

namespace {
// A plain Fast DDS subscriber, as PX4's agent side would be: PX4's type names and QoS.
template <class T, class Support>
class Px4Side : public fdds::DataReaderListener {
public:
    Px4Side(fdds::DomainParticipant* p, const std::string& topic) {
        fdds::TypeSupport type(new Support());
        type_name = type.get_type_name();
        type.register_type(p);
        auto* t = p->create_topic(topic, type_name, fdds::TOPIC_QOS_DEFAULT);
        fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
        q.reliability().kind = fdds::BEST_EFFORT_RELIABILITY_QOS;
        q.durability().kind = fdds::VOLATILE_DURABILITY_QOS;
        q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
        q.history().depth = 8;
        subscriber_ = p->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
        reader_ = subscriber_->create_datareader(t, q, this);
    }
    ~Px4Side() override { reader_->set_listener(nullptr); }
    void on_data_available(fdds::DataReader* r) override {
        T s;
        fdds::SampleInfo info;
        while (r->take_next_sample(&s, &info) == ReturnCode_t::RETCODE_OK) {
            if (!info.valid_data) continue;
            std::lock_guard lock(mutex);
            got.push_back(s);
        }
    }
    std::mutex mutex;
    std::vector<T> got;
    std::string type_name;

private:
    fdds::Subscriber* subscriber_ = nullptr;
    fdds::DataReader* reader_ = nullptr;
};

template <class F>
bool eventually(F&& f) {
    for (int i = 0; i < 2000; ++i) {
        if (f()) return true;
        std::this_thread::sleep_for(10ms);
    }
    return false;
}
}  // namespace

TEST(Px4Link, SetpointsReachAPx4SubscriberWithItsNamesTypesQosValuesAndFrame) {
    dw::dds::DdsConfig cfg;
    cfg.domain = dw::test::test_domain();
    dw::dds::Participant lab(cfg, "planner");
    auto* px4 = fdds::DomainParticipantFactory::get_instance()->create_participant(
        static_cast<fdds::DomainId_t>(cfg.domain), dw::dds::participant_qos(cfg, "px4-agent"));
    {
        using namespace px4_msgs::msg::dds_;
        const std::string ns = "uav" + std::to_string(::getpid());
        Px4Side<TrajectorySetpoint_, TrajectorySetpoint_PubSubType> traj(px4, "rt/" + ns + "/fmu/in/trajectory_setpoint");
        Px4Side<OffboardControlMode_, OffboardControlMode_PubSubType> mode(px4, "rt/" + ns + "/fmu/in/offboard_control_mode");
        Px4Side<VehicleCommand_, VehicleCommand_PubSubType> cmd(px4, "rt/" + ns + "/fmu/in/vehicle_command");
        EXPECT_EQ(traj.type_name, "px4_msgs::msg::dds_::TrajectorySetpoint_");
        EXPECT_EQ(mode.type_name, "px4_msgs::msg::dds_::OffboardControlMode_");
        EXPECT_EQ(cmd.type_name, "px4_msgs::msg::dds_::VehicleCommand_");

        // The vehicle's PX4 home is 1 m north and 0.5 m east of the lab's origin, on the floor.
        dw::planner::Px4Link link(lab, {ns}, {dw::physics::Vec3(1.0, 0.5, 0.0)});
        std::this_thread::sleep_for(1500ms);  // discovery; then a stream, as PX4 expects (> 2 Hz)
        link.start();
        dw::physics::Setpoint sp;
        sp.position = dw::physics::Vec3(0.2, -0.3, -1.9);
        sp.velocity = dw::physics::Vec3(0, 0.5, 0);
        sp.yaw_rad = 0.25;
        for (int i = 0; i < 50; ++i) {
            link.send({sp}, 1'700'000'000'000'000'000 + i * 20'000'000LL);
            std::this_thread::sleep_for(20ms);
        }
        link.land();
        ASSERT_TRUE(eventually([&] { std::lock_guard l(traj.mutex); return traj.got.size() >= 10; }));
        ASSERT_TRUE(eventually([&] { std::lock_guard l(cmd.mutex); return cmd.got.size() >= 3; }));
        ASSERT_TRUE(eventually([&] { std::lock_guard l(mode.mutex); return !mode.got.empty(); }));
        {
            std::lock_guard l(traj.mutex);
            const auto& t = traj.got.back();
            EXPECT_FLOAT_EQ(t.position()[0], -0.8f);  // lab NED minus PX4's home
            EXPECT_FLOAT_EQ(t.position()[1], -0.8f);
            EXPECT_FLOAT_EQ(t.position()[2], -1.9f);
            EXPECT_FLOAT_EQ(t.velocity()[1], 0.5f);
            EXPECT_FLOAT_EQ(t.yaw(), 0.25f);
            EXPECT_TRUE(std::isnan(t.yawspeed()));
            EXPECT_EQ(t.timestamp() % 20000, 0u);  // microseconds
        }
        {
            std::lock_guard l(mode.mutex);
            EXPECT_TRUE(mode.got.back().position());
            EXPECT_FALSE(mode.got.back().attitude());
        }
        std::lock_guard l(cmd.mutex);
        std::vector<std::uint32_t> kinds;
        for (const auto& c : cmd.got) kinds.push_back(c.command());
        ASSERT_GE(kinds.size(), 3u);
        EXPECT_EQ(kinds[0], dw::planner::kVehicleCmdDoSetMode);
        EXPECT_FLOAT_EQ(cmd.got[0].param1(), 1.0f);
        EXPECT_FLOAT_EQ(cmd.got[0].param2(), 6.0f);  // PX4_CUSTOM_MAIN_MODE_OFFBOARD
        EXPECT_EQ(kinds[1], dw::planner::kVehicleCmdArmDisarm);
        EXPECT_FLOAT_EQ(cmd.got[1].param1(), 1.0f);
        EXPECT_EQ(kinds.back(), dw::planner::kVehicleCmdNavLand);
        EXPECT_EQ(cmd.got[0].target_system(), 1);
        EXPECT_TRUE(cmd.got[0].from_external());
    }
    px4->delete_contained_entities();
    fdds::DomainParticipantFactory::get_instance()->delete_participant(px4);
}
