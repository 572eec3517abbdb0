#pragma once
// The online predictor: subscribes to the motion capture, forms every neighbour's state relative
// to the sufferer (velocity from the frames' camera stamps), and publishes the model's predicted
// wrench on predictor/wrench at the mocap rate, stamped with the input's time and carrying its
// age. The model file is watched: a new model is swapped in without a restart; a bad one is
// refused with one line and the old one kept.
#include <atomic>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "core/bounded_map.hpp"
#include "core/clock.hpp"
#include "dds/endpoint.hpp"
#include "dds/participant.hpp"
#include "dw/msg/Mocap.h"
#include "dw/msg/Prediction.h"
#include "flight/flight.hpp"
#include "physics/prediction_noise.hpp"
#include "predictor/dataset.hpp"
#include "predictor/model.hpp"

namespace dw::predictor {

// The neighbours of one frame: their states relative to the sufferer, and who they are.
struct FrameNeighbours {
    std::vector<RelState> x;
    std::vector<std::string> names;  // x[j]'s rigid body
    double t = 0;                    // the frame's stamp [s]
    double sufferer_height_m = 0;    // above the floor
};

// Relative states from a stream of frames (no DDS: tests and benchmarks call it directly).
class FrameFeatures {
public:
    // neighbours: the bodies that count as neighbours (empty: every tracked body but the sufferer).
    explicit FrameFeatures(std::string sufferer = flight::kSufferer, std::vector<std::string> neighbours = {},
                           double max_distance_m = 3.0)
        : sufferer_(std::move(sufferer)), neighbours_(std::move(neighbours)), max_distance_m_(max_distance_m) {}
    // The neighbours at this frame (at most kMaxNeighbours); nullopt if the sufferer is not tracked.
    std::optional<FrameNeighbours> update(const msg::MocapFrame& frame);
    std::size_t bodies_remembered() const { return history_.size(); }  // at most flight::kMaxBodies

private:
    struct History {
        std::deque<std::pair<double, std::array<double, 3>>> p;  // (t, position), last ~30 ms
    };
    std::array<double, 3> velocity(History& h, double t, const std::array<double, 3>& p);
    bool is_neighbour(const std::string& name) const;
    std::string sufferer_;
    std::vector<std::string> neighbours_;
    double max_distance_m_;
    // At most flight::kMaxBodies names: frames full of new names forget the oldest.
    BoundedMap<std::string, History> history_{flight::kMaxBodies};
};

struct NodeOptions {
    std::string model_path;
    std::string sufferer = flight::kSufferer;
    // A flight's meta.json (downwash-flight/1) describing the lab's bodies: its sufferer, its
    // neighbours and their parameters (mass, rotors, ...), which the models take per body as they do
    // on a recorded flight. Empty: the bodies are not known (each model's defaults).
    std::string vehicles_path;
    // A physics configuration whose noise model (the sufferer's class floor, the turbulence) gives
    // each prediction's 95 % interval on f_d, for a model that carries no physics of its own (a
    // physics model, or a correction composed with one, uses its own). Empty: none.
    std::string noise_path;
    double reload_check_s = 0.5;
};

// The lab's bodies as a recorded flight's source describes them, for predicting per body online:
// only meta.json's neighbours count as neighbours, each with its parameters. Throws dw::InputError
// naming the file when a body has no parameters there or there are more neighbours than the models take.
class OnlineBodies {
public:
    OnlineBodies(const flight::Meta& meta, const std::string& path);
    Sample sample(const FrameNeighbours& f) const;  // the frame as a dataset sample of this source
    const Source& source() const { return source_; }
    const std::string& sufferer() const { return sufferer_; }
    const std::vector<std::string>& neighbours() const { return neighbours_; }

private:
    std::string sufferer_;
    std::vector<std::string> neighbours_;
    Source source_;
    std::map<std::string, std::uint8_t> index_;  // neighbour name -> its place in source_.neighbours
};

class PredictorNode {
public:
    // Throws dw::InputError if the first model or the bodies' meta.json cannot be loaded.
    PredictorNode(dds::Participant& p, const NodeOptions& o, const Clock& clock);
    ~PredictorNode();
    PredictorNode(const PredictorNode&) = delete;
    PredictorNode& operator=(const PredictorNode&) = delete;

    std::uint64_t published() const { return published_.load(); }
    std::uint64_t reloads() const { return reloads_.load(); }
    // Mocap frames missing from the bridge's sequence since the first one received.
    std::uint64_t frames_lost() const { return reader_->lost(); }
    // Frames the model could not predict (a geometry the physics cannot take), left unpublished.
    std::uint64_t unpredicted() const { return unpredicted_.load(); }
    // Frames refused for a stamp off their stream's time (StampGate: garbled or forged), unpublished.
    std::uint64_t stray_stamps() const { return stray_stamps_.load(); }
    std::string model_name() const;

private:
    void on_frame(const msg::MocapFrame& frame);
    Wrench6 predict(const ForceModel& model, const FrameNeighbours& f) const;
    // The 95 % half width of f_d predicted at stand time t, 0: none.
    double f_d_interval(const ForceModel& model, double t, double f_d);
    void watch();

    NodeOptions options_;
    const Clock& clock_;
    mutable std::mutex mutex_;
    std::shared_ptr<const ForceModel> model_;
    std::optional<OnlineBodies> bodies_;
    std::optional<physics::PhysicsConfig> noise_;  // NodeOptions::noise_path
    FrameFeatures features_;
    dds::Writer<msg::WrenchPrediction> writer_;
    std::optional<dds::Reader<msg::MocapFrame>> reader_;  // subscribed once the writer's readers are awaited
    std::atomic<std::uint64_t> published_{0}, reloads_{0}, unpredicted_{0}, stray_stamps_{0};
    StampGate stamps_;             // on the reader's thread only
    physics::PushRate push_rate_;  // of the model named push_rate_model_; on the reader's thread only
    std::string push_rate_model_;
    std::atomic<bool> stop_{false};
    std::thread watcher_;
};

}  // namespace dw::predictor
