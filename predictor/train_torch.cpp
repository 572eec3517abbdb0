// The only translation unit that includes libtorch (it compiles slowly).
#include <torch/torch.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "predictor/train.hpp"
#include "predictor/train_module.hpp"

namespace dw::predictor {

namespace {

torch::nn::Sequential mlp(int in, int hidden, int out) {
    return torch::nn::Sequential(torch::nn::Linear(in, hidden), torch::nn::SiLU(), torch::nn::Linear(hidden, hidden),
                                 torch::nn::SiLU(), torch::nn::Linear(hidden, out));
}

Mlp export_mlp(torch::nn::Sequential& seq) {
    Mlp m;
    const auto n = seq->size();
    for (std::size_t i = 0; i < n; ++i) {
        auto lin = seq[i]->as<torch::nn::Linear>();
        if (!lin) continue;
        const auto w = lin->weight.detach().contiguous().to(torch::kFloat32);
        const auto b = lin->bias.detach().contiguous().to(torch::kFloat32);
        Layer l;
        l.w.resize(w.size(0), w.size(1));
        for (int64_t r = 0; r < w.size(0); ++r)
            for (int64_t c = 0; c < w.size(1); ++c) l.w(r, c) = w[r][c].item<float>();
        l.b.resize(b.size(0));
        for (int64_t r = 0; r < b.size(0); ++r) l.b[r] = b[r].item<float>();
        l.silu = i + 1 < n;  // every Linear but the last is followed by SiLU
        m.layers.push_back(std::move(l));
    }
    return m;
}

// The training set in the model's normalisation: one row of features per neighbour there is, and
// per sample the rows of its neighbours, so that a sample with one neighbour costs the networks one
// evaluation, not kMaxNeighbours.
struct Tensors {
    torch::Tensor x;      // [neighbours, kFeatureSize]
    torch::Tensor owner;  // [neighbours]: the sample each row of x belongs to
    torch::Tensor slots;  // [samples, kMaxNeighbours]: the row of x of each neighbour, -1 where none
    torch::Tensor y;      // [samples, 6]
};

Tensors tensors(const Dataset& d, const LearntModel& norm) {
    const auto n = static_cast<int64_t>(d.samples.size());
    int64_t rows = 0;
    for (const auto& s : d.samples) rows += s.k;
    auto x = torch::zeros({rows, kFeatureSize});
    auto owner = torch::zeros({rows}, torch::kLong);
    auto slots = torch::full({n, kMaxNeighbours}, -1, torch::kLong);
    auto y = torch::zeros({n, 6});
    auto xa = x.accessor<float, 2>();
    auto oa = owner.accessor<int64_t, 1>();
    auto sa = slots.accessor<int64_t, 2>();
    auto ya = y.accessor<float, 2>();
    int64_t row = 0;
    for (int64_t i = 0; i < n; ++i) {
        const auto& s = d.samples[static_cast<std::size_t>(i)];
        const Bodies bodies = bodies_of(s, d.sources[static_cast<std::size_t>(s.source)]);
        for (int j = 0; j < s.k; ++j, ++row) {
            sa[i][j] = row;
            oa[row] = i;
            const Features f = norm.features(s.neighbours(), static_cast<std::size_t>(j), bodies);
            for (std::size_t a = 0; a < f.size(); ++a) xa[row][static_cast<int64_t>(a)] = norm.normalised(f, a);
        }
        for (std::size_t a = 0; a < 6; ++a)
            ya[i][static_cast<int64_t>(a)] = static_cast<float>(s.y[a]) / norm.output_scale[a];
    }
    return {x, owner, slots, y};
}

// Some samples' neighbours: their feature rows, and which of the samples (0 .. size) each belongs to.
struct Batch {
    torch::Tensor x, owner;
    int64_t size;
};

Batch whole(const Tensors& t) { return {t.x, t.owner, t.y.size(0)}; }

Batch batch(const Tensors& t, const torch::Tensor& samples) {
    const auto slots = t.slots.index_select(0, samples);
    const auto valid = slots.ge(0);
    const auto owner = torch::arange(samples.size(0), torch::kLong).unsqueeze(1).expand_as(slots).masked_select(valid);
    return {t.x.index_select(0, slots.masked_select(valid)), owner, samples.size(0)};
}

// Per-feature mean and spread over every neighbour. The wrench is scaled by one RMS for the three
// forces and one for the three moments (no offset: the sum structure must give 0 with nobody near):
// the loss is then an error in newtons, dominated by the axes that carry a signal, not a per-axis
// ratio in which an axis of pure noise (f_n, f_e under a hover) weighs as much as f_d.
void normalise(const Dataset& train, LearntModel& m) {
    std::array<double, kFeatureSize> sum{}, sq{}, count{};  // per feature: a mass may be unknown (NaN)
    std::array<double, kFeatureSize> lo, hi;                // its range: a single value teaches nothing
    lo.fill(std::numeric_limits<double>::infinity());
    hi.fill(-std::numeric_limits<double>::infinity());
    std::array<double, 6> ysq{};
    for (const auto& s : train.samples) {
        const Bodies bodies = bodies_of(s, train.sources[static_cast<std::size_t>(s.source)]);
        for (std::size_t j = 0; j < static_cast<std::size_t>(s.k); ++j) {
            const Features f = features_of(s.x[j], bodies.neighbour_kg[j], bodies.sufferer_kg);
            for (std::size_t a = 0; a < f.size(); ++a) {
                if (std::isnan(f[a])) continue;
                sum[a] += f[a];
                sq[a] += f[a] * f[a];
                count[a] += 1;
                lo[a] = std::min(lo[a], f[a]);
                hi[a] = std::max(hi[a], f[a]);
            }
        }
        for (std::size_t a = 0; a < 6; ++a) ysq[a] += s.y[a] * s.y[a];
    }
    if (count[0] == 0) throw InputError("training: no sample has a neighbour");
    for (std::size_t a = 0; a < sum.size(); ++a) {
        const double mean = count[a] > 0 ? sum[a] / count[a] : 0.0;
        m.input_mean[a] = static_cast<float>(mean);
        const double spread = std::sqrt(std::max(0.0, sq[a] / std::max(1.0, count[a]) - mean * mean));
        m.input_std[a] = !(hi[a] > lo[a]) ? kUnvariedStd : static_cast<float>(std::max(1e-3, spread));
    }
    m.input_mean[kOverlapFeature] = 0;  // it weighs phi's term as it is (model.hpp)
    m.input_std[kOverlapFeature] = 1;
    const auto n = static_cast<double>(train.samples.size());
    for (std::size_t group = 0; group < 6; group += 3) {
        const double rms = std::sqrt((ysq[group] + ysq[group + 1] + ysq[group + 2]) / (3 * n));
        for (std::size_t a = group; a < group + 3; ++a) m.output_scale[a] = static_cast<float>(std::max(1e-3, rms));
    }
}

// The model's kind, structure and normalisation: its own, or a sum baseline's (Deep Sets
// learning the residual on it: its normalisation and its psi).
void prepare(LearntModel& m, const Dataset& train, const TrainOptions& o, const LearntModel* baseline) {
    m.kind = o.kind;
    m.structure = structure_of(o.kind);
    if (!baseline) {
        normalise(train, m);
        return;
    }
    if (m.structure != Structure::deep_sets || baseline->structure != Structure::sum)
        throw InputError(log::cat(
            "training: a baseline is a sum model (naive_linear or learnt_linear) under a deep_sets model, not ",
            baseline->kind, " under ", o.kind));
    m.input_mean = baseline->input_mean;
    m.input_std = baseline->input_std;
    m.output_scale = baseline->output_scale;
    m.baseline = baseline->phi;
}

// What the model file records about its training.
std::string training_metadata(const Dataset& train, const Dataset& validation, const TrainOptions& o,
                              const TrainResult& r, const LearntModel* baseline) {
    nlohmann::json sources = nlohmann::json::array();
    for (const auto& s : train.sources) sources.push_back({{"name", s.name}, {"formation", s.formation}});
    return nlohmann::json{{"trained_on", sources},
                          {"train_samples", train.samples.size()},
                          {"validation_samples", validation.samples.size()},
                          {"split", o.split},
                          {"epochs", r.epochs},
                          {"best_epoch", r.best_epoch},
                          {"best_validation_mse_normalised", r.best_validation_loss},
                          {"seed", o.seed},
                          {"from_zero", o.from_zero},
                          {"hidden", o.hidden},
                          {"latent", o.latent},
                          {"learning_rate", o.learning_rate},
                          {"batch", o.batch},
                          {"baseline", baseline ? baseline->kind : "none"},
                          {"training_seconds", r.seconds}}
        .dump();
}

// The networks and how their outputs combine (model.hpp): a sum model pools phi's six outputs over
// the neighbours; Deep Sets feeds the pooled latent through rho — on a baseline (residual), each
// neighbour's term weighed by its jet overlap, less rho(0), plus the baseline's psi summed over the
// neighbours (psi sees the overlap as 0: one neighbour at a time).
struct Net {
    torch::nn::Sequential phi, rho, psi;
    bool deep_sets, residual;
    torch::Tensor without_overlap;  // multiplies the features: 1, but 0 at kOverlapFeature

    torch::Tensor forward(const Batch& b) {
        auto pool = [&](const torch::Tensor& terms) {  // the sum over each sample's neighbours
            return torch::zeros({b.size, terms.size(1)}).index_add(0, b.owner, terms);
        };
        if (!deep_sets) return pool(phi->forward(b.x));
        if (!residual) return rho->forward(pool(phi->forward(b.x)));
        const auto overlap = b.x.slice(1, kOverlapFeature, kOverlapFeature + 1);
        const auto pooled = pool(phi->forward(b.x) * overlap);
        const auto base = pool(psi->forward(b.x * without_overlap));
        return rho->forward(pooled) - rho->forward(torch::zeros({1, pooled.size(1)})) + base;
    }
    torch::Tensor loss(const Tensors& t) { return torch::mse_loss(forward(whole(t)), t.y); }
};

// A trained network's weights into a torch network of the same shape.
void import_mlp(const Mlp& from, torch::nn::Sequential& to) {
    torch::NoGradGuard no_grad;
    std::size_t k = 0;
    for (std::size_t i = 0; i < to->size(); ++i) {
        auto lin = to[i]->as<torch::nn::Linear>();
        if (!lin) continue;
        const Layer& l = from.layers.at(k++);
        if (lin->weight.size(0) != l.w.rows() || lin->weight.size(1) != l.w.cols())
            throw InputError(log::cat("training: the baseline's layer ", k, " is ", l.w.rows(), " x ", l.w.cols(),
                                      ", this model's ", lin->weight.size(0), " x ", lin->weight.size(1),
                                      " (train both with the same --hidden)"));
        for (int64_t r = 0; r < l.w.rows(); ++r) {
            for (int64_t c = 0; c < l.w.cols(); ++c) lin->weight[r][c] = l.w(r, c);
            lin->bias[r] = l.b[r];
        }
    }
}

// The networks, their initial weights drawn from torch's global generator: seeded and drawn under
// one lock, so that trainings running at once (the study's generalisation) start as they would alone.
// On a baseline, psi starts as the baseline's and rho's last layer at zero: before any step the
// model is its baseline.
Net make_net(const LearntModel& m, const TrainOptions& o) {
    static std::mutex global_generator;
    const std::lock_guard lock(global_generator);
    torch::manual_seed(o.seed);
    const bool deep = m.structure == Structure::deep_sets;
    Net net{mlp(kFeatureSize, o.hidden, deep ? o.latent : 6),
            mlp(o.latent, o.hidden, 6),
            m.residual() ? mlp(kFeatureSize, o.hidden, 6) : torch::nn::Sequential(),  // psi: on a baseline only
            deep,
            m.residual(),
            torch::ones({1, kFeatureSize})};
    net.without_overlap[0][kOverlapFeature] = 0;
    auto zero_last = [](torch::nn::Sequential& s) {
        torch::NoGradGuard no_grad;
        auto last = s[s->size() - 1]->as<torch::nn::Linear>();
        last->weight.zero_();
        last->bias.zero_();
    };
    if (net.residual) {
        import_mlp(m.baseline, net.psi);
        zero_last(net.rho);
    } else if (o.from_zero && !deep) {
        zero_last(net.phi);
    }
    return net;
}

// One pass over the training samples in shuffled minibatches; the mean batch loss.
double train_epoch(Net& net, torch::optim::Adam& adam, const Tensors& tr, const TrainOptions& o,
                   const torch::Generator& gen) {
    const int64_t n = tr.y.size(0);
    const auto perm = torch::randperm(n, gen, torch::kLong);
    double total = 0;
    int64_t batches = 0;
    for (int64_t b = 0; b < n; b += o.batch) {
        throw_if_stopped(o.stop, "training");
        const auto idx = perm.slice(0, b, std::min(n, b + o.batch));
        adam.zero_grad();
        auto loss = torch::mse_loss(net.forward(batch(tr, idx)), tr.y.index_select(0, idx));
        loss.backward();
        adam.step();
        total += loss.item<double>();
        ++batches;
    }
    return total / static_cast<double>(batches);
}

void halve_learning_rate(torch::optim::Adam& adam) {
    for (auto& g : adam.param_groups()) {
        auto& options = static_cast<torch::optim::AdamOptions&>(g.options());
        options.lr(options.lr() * 0.5);
    }
}

}  // namespace

TrainResult train_with_torch(const Dataset& train, const Dataset& validation, const TrainOptions& o,
                             const LearntModel* baseline) {
    if (train.samples.empty()) throw InputError("training: no samples on the training legs");
    if (validation.samples.empty()) throw InputError("training: no samples on the validation legs");
    const auto core = o.cores ? o.cores->take(o.turn, o.stop, "training") : Cores::Pass{};
    const auto started = std::chrono::steady_clock::now();
    torch::set_num_threads(o.threads);

    TrainResult r;
    LearntModel& m = r.model;
    prepare(m, train, o, baseline);

    const Tensors tr = tensors(train, m), va = tensors(validation, m);
    Net net = make_net(m, o);
    std::vector<torch::Tensor> params = net.phi->parameters();
    if (net.deep_sets)
        for (auto& p : net.rho->parameters()) params.push_back(p);
    // On a baseline its psi trains on with the rest (from the baseline's weights): a sum model fitted
    // to flights where jets merge is bent by them, and rho now takes the merging.
    if (net.residual)
        for (auto& p : net.psi->parameters()) params.push_back(p);
    torch::optim::Adam adam(params, torch::optim::AdamOptions(o.learning_rate));

    auto snapshot = [&] {
        std::vector<torch::Tensor> s;
        for (auto& p : params) s.push_back(p.detach().clone());
        return s;
    };
    auto best = snapshot();
    r.best_validation_loss = INFINITY;
    if (baseline || o.from_zero) {  // the baseline alone (or zero) is the score to beat
        torch::NoGradGuard no_grad;
        r.best_validation_loss = net.loss(va).item<double>();
    }
    auto gen = torch::make_generator<torch::CPUGeneratorImpl>(o.seed);
    int since_best = 0;
    for (int epoch = 1; epoch <= o.max_epochs; ++epoch) {
        const double train_loss = train_epoch(net, adam, tr, o, gen);
        double val = 0;
        {
            torch::NoGradGuard no_grad;
            val = net.loss(va).item<double>();
        }
        r.epochs = epoch;
        if (o.progress) o.progress(epoch, train_loss, val);
        if (val < r.best_validation_loss - 1e-5) {
            r.best_validation_loss = val;
            r.best_epoch = epoch;
            best = snapshot();
            since_best = 0;
        } else if (++since_best >= o.patience) {
            break;
        } else if (since_best % std::max(1, o.patience / 3) == 0) {  // plateau: halve the step
            halve_learning_rate(adam);
        }
    }
    {
        torch::NoGradGuard no_grad;
        for (std::size_t i = 0; i < params.size(); ++i) params[i].copy_(best[i]);
    }
    m.phi = export_mlp(net.phi);
    if (m.structure == Structure::deep_sets) m.rho = export_mlp(net.rho);
    if (net.residual) m.baseline = export_mlp(net.psi);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    m.metadata_json = training_metadata(train, validation, o, r, baseline);
    return r;
}

}  // namespace dw::predictor

// The module's one entry (train.cpp loads it): train_with_torch, as a TrainFunction.
extern "C" dw::predictor::TrainFunction dw_training_entry() { return &dw::predictor::train_with_torch; }
