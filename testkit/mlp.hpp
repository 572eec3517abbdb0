#pragma once
// A multilayer perceptron with normally distributed weights and biases (SiLU between layers,
// none after the last): for inference tests and benchmarks, where the weights' values do not
// matter but their sizes do.
#include <random>
#include <vector>

#include "predictor/model.hpp"

namespace dw::testkit {

inline predictor::Mlp random_mlp(std::mt19937& rng, const std::vector<int>& sizes, float sd) {
    std::normal_distribution<float> g(0, sd);
    predictor::Mlp m;
    for (std::size_t i = 0; i + 1 < sizes.size(); ++i) {
        predictor::Layer l;
        l.w = Eigen::MatrixXf(sizes[i + 1], sizes[i]).unaryExpr([&](float) { return g(rng); });
        l.b = Eigen::VectorXf(sizes[i + 1]).unaryExpr([&](float) { return g(rng); });
        l.silu = i + 2 < sizes.size();
        m.layers.push_back(l);
    }
    return m;
}

}  // namespace dw::testkit
