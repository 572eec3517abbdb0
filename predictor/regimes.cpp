#include "predictor/regimes.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>
#include <tuple>

#include "core/log.hpp"
#include "core/numbers.hpp"
#include "core/shutdown.hpp"
#include "core/stats.hpp"
#include "plot/draw.hpp"
#include "plot/png.hpp"
#include "predictor/evaluate.hpp"

namespace dw::predictor {

namespace {

constexpr std::size_t kMinPieces = 6;         // pieces of held-out legs in a band, or the band is left out
constexpr std::size_t kMinPieceSamples = 10;  // shorter pieces (a leg's ragged end) are left out

struct PieceErrors {
    double sum_sq = 0, deep_sq = 0, truth_sq = 0;
    std::size_t n = 0;
    int k_max = 0;  // the most neighbours in the piece
};
using PieceKey = std::tuple<int, int, long>;  // source, leg, piece of the leg

RegimeRow judge(const std::string& formation, double altitude, const std::map<PieceKey, PieceErrors>& pieces,
                const RegimeOptions& o) {
    RegimeRow r;
    r.formation = formation;
    r.altitude_m = altitude;
    double s = 0, d = 0, t = 0, n = 0;
    std::vector<double> diff;
    std::set<std::pair<int, int>> legs;
    int k_max = 0;
    for (const auto& [key, e] : pieces) {
        if (e.n < kMinPieceSamples) continue;
        k_max = std::max(k_max, e.k_max);
        s += e.sum_sq, d += e.deep_sq, t += e.truth_sq, n += static_cast<double>(e.n);
        diff.push_back((e.sum_sq - e.deep_sq) / static_cast<double>(e.n));
        legs.insert({std::get<0>(key), std::get<1>(key)});
    }
    r.legs = legs.size();
    if (diff.size() < kMinPieces || t <= 0) return r;
    r.signal_rms = std::sqrt(t / n);
    r.explained = 1 - std::min(s, d) / t;
    r.gain = s > 0 ? 1 - d / s : 0;
    r.z = paired_z(diff);
    if (r.explained < o.min_explained) r.regime = Regime::chaotic;
    else if (k_max > 1 && r.z >= o.min_z && r.gain >= o.min_gain) r.regime = Regime::non_linear;
    else r.regime = Regime::linear;
    return r;
}

}  // namespace

const char* regime_name(Regime r) {
    switch (r) {
        case Regime::chaotic: return "chaotic";
        case Regime::linear: return "linear";
        case Regime::non_linear: return "non-linear";
    }
    return "?";
}

LearntModel sum_to_compare(const LearntModel& deep, const LearntModel& learnt_linear) {
    return deep.residual() ? deep.sum_part() : learnt_linear;
}

std::vector<RegimeRow> classify_regimes(const ForceModel& sum, const ForceModel& deep, const Dataset& test,
                                        const std::vector<double>& altitudes_m, const RegimeOptions& o,
                                        std::stop_token stop) {
    std::vector<RegimeRow> rows;
    for (const double altitude : altitudes_m) {
        throw_if_stopped(stop, "the regimes");
        const Dataset band = test.in_altitude_band(altitude, o.band_m);
        std::map<std::string, std::map<PieceKey, PieceErrors>> by_formation;
        for (const auto& s : band.samples) {
            const auto& source = band.sources[static_cast<std::size_t>(s.source)];
            if (s.leg < 0 || s.k == 0 || !source.measured[kFdAxis]) continue;
            auto& e = by_formation[source.formation][{s.source, s.leg, std::lround(std::floor(s.t / o.piece_s))}];
            const double y = s.y[kFdAxis];
            const double ps = predict(sum, band, s)[kFdAxis] - y, pd = predict(deep, band, s)[kFdAxis] - y;
            e.sum_sq += ps * ps, e.deep_sq += pd * pd, e.truth_sq += y * y, ++e.n;
            e.k_max = std::max(e.k_max, s.k);
        }
        for (const auto& [formation, pieces] : by_formation) {
            RegimeRow r = judge(formation, altitude, pieces, o);
            if (r.signal_rms > 0) rows.push_back(std::move(r));
        }
    }
    return rows;
}

std::string regimes_markdown(const std::vector<RegimeRow>& rows, const RegimeOptions& o) {
    std::ostringstream out;
    out << "Held-out legs, f_d, in pieces of " << o.piece_s << " s. **chaotic**: neither model explains "
        << o.min_explained * 100
        << " % of the measured mean square; **non-linear**: Deep Sets better than its own sum part (Σ psi) with paired "
           "z ≥ "
        << o.min_z << " and ≥ " << o.min_gain * 100 << " % less squared error; **linear**: otherwise.\n\n"
        << "| formation | altitude | regime | held-out legs | f_d RMS [N] | explained | Deep Sets' gain over the sum | "
           "z |\n"
        << "|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : rows)
        out << "| " << r.formation << " | " << r.altitude_m << " m | " << regime_name(r.regime) << " | " << r.legs
            << " | " << fixed(r.signal_rms, 3) << " | " << fixed(r.explained * 100, 0) << " % | "
            << fixed(r.gain * 100, 0) << " % | " << fixed(r.z, 1) << " |\n";
    return out.str();
}

std::string regimes_csv(const std::vector<RegimeRow>& rows) {
    std::ostringstream out;
    out << "formation,altitude_m,regime,legs,f_d_rms,explained,gain,z\n";
    for (const auto& r : rows)
        out << CsvRow()
                   .text(r.formation)
                   .num(r.altitude_m)
                   .text(regime_name(r.regime))
                   .count(r.legs)
                   .num(r.signal_rms)
                   .num(r.explained)
                   .num(r.gain)
                   .num(r.z)
                   .line();
    return out.str();
}

void draw_regime_map(const std::vector<RegimeRow>& rows, const std::string& png) {
    std::vector<std::string> formations;
    std::vector<double> altitudes;
    for (const auto& r : rows) {
        if (std::find(formations.begin(), formations.end(), r.formation) == formations.end())
            formations.push_back(r.formation);
        if (std::find(altitudes.begin(), altitudes.end(), r.altitude_m) == altitudes.end())
            altitudes.push_back(r.altitude_m);
    }
    std::sort(altitudes.begin(), altitudes.end());
    const int left = 200, top = 70, cw = 200, ch = 60;
    const int rows_n = static_cast<int>(formations.size()), cols = static_cast<int>(altitudes.size());
    cv::Mat img(top + rows_n * ch + 60, left + cols * cw + 20, CV_8UC3, cv::Scalar(255, 255, 255));
    plot::text(img, "Regimes of the aggregate downwash (held-out legs, f_d)", {10, 25}, 0.6);
    auto colour = [](Regime r) {  // BGR
        switch (r) {
            case Regime::chaotic: return cv::Scalar(200, 200, 200);
            case Regime::linear: return cv::Scalar(235, 190, 120);
            case Regime::non_linear: return cv::Scalar(90, 165, 245);
        }
        return cv::Scalar(255, 255, 255);
    };
    for (int c = 0; c < cols; ++c)
        plot::text(img, log::cat(altitudes[static_cast<std::size_t>(c)], " m above"),
                   {left + c * cw + cw / 2, top - 10}, 0.5, 1);
    for (int i = 0; i < rows_n; ++i)
        plot::text(img, formations[static_cast<std::size_t>(i)], {10, top + i * ch + ch / 2 + 5}, 0.5);
    for (const auto& r : rows) {
        const int i =
            static_cast<int>(std::find(formations.begin(), formations.end(), r.formation) - formations.begin());
        const int c = static_cast<int>(std::find(altitudes.begin(), altitudes.end(), r.altitude_m) - altitudes.begin());
        const cv::Rect cell(left + c * cw + 2, top + i * ch + 2, cw - 4, ch - 4);
        cv::rectangle(img, cell, colour(r.regime), cv::FILLED);
        plot::text(img, regime_name(r.regime), {cell.x + cell.width / 2, cell.y + 24}, 0.55, 1);
        plot::text(img, log::cat("gain ", fixed(r.gain * 100, 0), " %, z ", fixed(r.z, 1)),
                   {cell.x + cell.width / 2, cell.y + 46}, 0.42, 1);
    }
    int x = left;
    for (const Regime g : {Regime::chaotic, Regime::linear, Regime::non_linear}) {
        const int y = top + rows_n * ch + 20;
        cv::rectangle(img, cv::Rect(x, y, 18, 18), colour(g), cv::FILLED);
        plot::text(img, regime_name(g), {x + 24, y + 14}, 0.45);
        x += 150;
    }
    plot::write_png(img, png);
}

}  // namespace dw::predictor
