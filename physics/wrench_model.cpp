#include "physics/wrench_model.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

// x86-64: the physics' inner loops are also built for AVX2 (four doubles at once; no FMA, so each
// value is the same whichever build runs) and the loader picks the one the CPU can run (GCC's
// function multiversioning).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define DW_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define DW_VECTOR_CLONES
#endif

namespace dw::physics {

struct WrenchModel::Scratch {
    std::vector<double> ux, uy, uz;  // the air at each cell
    std::vector<double> fx, fy, fz;  // each cell's drag (WrenchModel::drag)
    void reset(std::size_t n) {
        ux.assign(n, 0.0);
        uy.assign(n, 0.0);
        uz.assign(n, 0.0);
        fx.resize(n);
        fy.resize(n);
        fz.resize(n);
    }
};

Planform Planform::make(const SuffererParams& s) {
    Planform p;
    const double R = s.vehicle.prop_radius_m;
    const double arm = 0.5 * s.vehicle.motor_distance_m;  // centre to motor
    const int rotors = s.vehicle.rotors;
    auto add = [&](double x, double y, double a) {
        p.x.push_back(x);
        p.y.push_back(y);
        p.area.push_back(a);
    };
    for (int k = 0; k < rotors; ++k) {
        // X configuration: the first motor at 45° (front right).
        const double phi = M_PI / 4 + 2 * M_PI * k / rotors;
        const double cx = arm * std::cos(phi), cy = arm * std::sin(phi);
        p.rotor_centre.push_back({cx, cy});
        p.rotor_area.push_back(M_PI * R * R);
        // Ring 0 is a centre disc; rings 1.. are annuli of equal width split into sectors.
        const double dr = R / s.disc_rings;
        const std::size_t first = p.size();
        add(cx, cy, M_PI * dr * dr);
        for (int ring = 1; ring < s.disc_rings; ++ring) {
            const double r0 = ring * dr, r1 = (ring + 1) * dr;
            const double rc = 2.0 / 3.0 * (r1 * r1 * r1 - r0 * r0 * r0) / (r1 * r1 - r0 * r0);  // centroid radius
            const double a = M_PI * (r1 * r1 - r0 * r0) / s.disc_sectors;
            for (int sec = 0; sec < s.disc_sectors; ++sec) {
                const double th = 2 * M_PI * (sec + 0.5) / s.disc_sectors;
                add(cx + rc * std::cos(th), cy + rc * std::sin(th), a);
            }
        }
        p.rotor_cells.push_back({first, p.size()});
        // The arm between the body and the disc.
        const double inner = 0.5 * s.body_size_m * std::sqrt(2.0), outer = arm - R;
        if (outer > inner && s.arm_width_m > 0) {
            const double mid = 0.5 * (inner + outer);
            add(mid * std::cos(phi), mid * std::sin(phi), (outer - inner) * s.arm_width_m);
        }
    }
    if (s.body_size_m > 0) {
        const double h = 0.25 * s.body_size_m;  // 2x2 cells
        const double a = 0.25 * s.body_size_m * s.body_size_m;
        for (double bx : {-h, h}) {
            for (double by : {-h, h}) add(bx, by, a);
        }
    }
    return p;
}

WrenchModel::WrenchModel(const PhysicsConfig& config)
    : config_(config), planform_(Planform::make(config.sufferer)), neighbour_jet_(Jet::make(config.neighbour, config)) {
    config_.sufferer = sufferer_as(config_, config_.sufferer.vehicle);  // its class's drag and thrust loss
    half_rho_cd_ = 0.5 * config_.air_density_kg_m3 * config_.sufferer.drag_coefficient;
    half_rho_clat_ = 0.5 * config_.air_density_kg_m3 * config_.sufferer.lateral_drag_coefficient;
    for (const auto* t : effect_types()) {
        if (t->stage() != Stage::air || !t->enabled(config_.effects)) continue;
        air_effects_.push_back(t);
        if (!regrouper_ && t->regroups_jets()) regrouper_ = t;
        if (delay_scale_ == 0) delay_scale_ = t->transport_delay_scale(config_.effects);
    }
}

Producer WrenchModel::producer(const Vec3& position, const Vec3& velocity) const {
    Producer p;
    p.position = position;
    p.velocity = velocity;
    p.jet = neighbour_jet_;
    return p;
}

void WrenchModel::add_velocity(const Vec3& suf, const Producer& p, double weight, Scratch& sc) const {
    add_velocity(suf, planform_.x.data(), planform_.y.data(), planform_.size(), p, weight, sc.ux.data(), sc.uy.data(),
                 sc.uz.data());
}

namespace {

// The Bauersfeld jet's speeds at depth s > 0 below its producer and squared distance r2 from its
// axis, with one division: with c = c_half, xi = s/l + origin and q = 1 / (c² xi² + b r2) (b the
// profile's), U_c / (1 + b r2 / (c xi)²)² = k_c c⁴ xi³ q², and the entrainment term
// U_c w / (c xi) (d⁻² - d⁻¹/2) with d⁻¹ = c² xi² q becomes k_c w (c³ xi² q² - c q / 2) (jet.hpp).
// Cells at s <= 0 get zero speeds (their gain is 0; q is at most 1 / kMinJetDenominator_m2, so
// nothing overflows even at the jet's virtual origin): no branch in the loop, so the compiler can
// take two or four cells at once.
inline constexpr double kMinJetDenominator_m2 = 1e-18;
struct BauersfeldTerms {
    Jet jet;                                       // a copy: nothing the loop writes can change it
    double c2, axial, radial_q2, radial_q, delay;  // delay: τ(s) = delay x jet.descent_numerator(s)
    BauersfeldTerms(const Jet& j, double delay_scale, bool radial)
        : jet(j),
          c2(j.c_half * j.c_half),
          axial(j.k_centre * c2 * c2),
          radial_q2(radial ? j.k_centre * j.k.width * c2 * j.c_half : 0.0),
          radial_q(radial ? 0.5 * j.k_centre * j.k.width * j.c_half : 0.0),
          delay(delay_scale > 0 ? delay_scale / j.descent_speed() : 0.0) {}
};

}  // namespace

DW_VECTOR_CLONES void WrenchModel::add_velocity(const Vec3& suf, const double* __restrict cx,
                                                const double* __restrict cy, std::size_t n, const Producer& p,
                                                double weight, double* __restrict ux, double* __restrict uy,
                                                double* __restrict uz) const {
    const Jet& jet = p.jet;
    const double delay_scale = delay_scale_;
    if (jet.model != JetModelKind::bauersfeld) {
        add_velocity_jain(suf, cx, cy, n, p, weight, delay_scale, ux, uy, uz);
        return;
    }
    const BauersfeldTerms t(jet, delay_scale, config_.radial_inflow);
    const double ax = p.axis.x(), ay = p.axis.y(), az = p.axis.z();
    // The producer's velocity matters only to the transport delay (a NaN one is harmless without it).
    const Vec3 v = t.delay > 0 ? p.velocity : Vec3::Zero();
    const double vx = v.x(), vy = v.y(), vz = v.z();
    const double ox = suf.x() - p.position.x(), oy = suf.y() - p.position.y(), oz = suf.z() - p.position.z();
    const double gain = weight * p.gust;
    for (std::size_t i = 0; i < n; ++i) {
        double dx = ox + cx[i], dy = oy + cy[i], dz = oz;
        const double s0 = std::max(dx * ax + dy * ay + dz * az, 0.0);
        // The air at depth s left the producer τ(s) ago, when it was at p - v τ (the transport delay a flow effect sets).
        const double tau = t.delay * t.jet.descent_numerator(s0);
        dx += vx * tau;
        dy += vy * tau;
        dz += vz * tau;
        const double s_raw = dx * ax + dy * ay + dz * az;
        const double g = s_raw > 0 ? gain : 0.0, s = std::max(s_raw, 0.0);
        const double rx = dx - s * ax, ry = dy - s * ay, rz = dz - s * az;
        const double r2 = rx * rx + ry * ry + rz * rz;
        const double xi = s * t.jet.inv_l + t.jet.k.origin, c2xi2 = t.c2 * xi * xi;
        const double q = 1.0 / std::max(c2xi2 + kProfileB * r2, kMinJetDenominator_m2);
        const double u_axial = g * t.axial * xi * xi * xi * q * q;
        const double u_radial_over_r = g * (t.radial_q2 * xi * xi * q * q - t.radial_q * q);
        ux[i] += u_axial * ax + u_radial_over_r * rx;
        uy[i] += u_axial * ay + u_radial_over_r * ry;
        uz[i] += u_axial * az + u_radial_over_r * rz;
    }
}

void WrenchModel::add_velocity_jain(const Vec3& suf, const double* cx, const double* cy, std::size_t n,
                                    const Producer& p, double weight, double delay_scale, double* ux, double* uy,
                                    double* uz) const {
    const Jet& jet = p.jet;
    const double ax = p.axis.x(), ay = p.axis.y(), az = p.axis.z();
    const double ox = suf.x() - p.position.x(), oy = suf.y() - p.position.y(), oz = suf.z() - p.position.z();
    const double gain = weight * p.gust;
    for (std::size_t i = 0; i < n; ++i) {
        double dx = ox + cx[i], dy = oy + cy[i], dz = oz;
        double s = dx * ax + dy * ay + dz * az;
        if (delay_scale > 0 && s > 0) {
            const double tau = delay_scale * jet.transport_delay(s);
            dx += p.velocity.x() * tau;
            dy += p.velocity.y() * tau;
            dz += p.velocity.z() * tau;
            s = dx * ax + dy * ay + dz * az;
        }
        if (s <= 0) continue;
        const double rx = dx - s * ax, ry = dy - s * ay, rz = dz - s * az;
        const double u_axial = gain * jet.axial(std::sqrt(rx * rx + ry * ry + rz * rz), s);
        ux[i] += u_axial * ax;
        uy[i] += u_axial * ay;
        uz[i] += u_axial * az;
    }
}

namespace {

// Each cell's bluff-body drag from the air there (four cells at once with AVX2; drag() sums them).
DW_VECTOR_CLONES void cell_drag(std::size_t n, const double* __restrict area, const double* __restrict ux,
                                const double* __restrict uy, const double* __restrict uz, double half_rho_cd,
                                double half_rho_clat, double* __restrict fx, double* __restrict fy,
                                double* __restrict fz) {
    for (std::size_t i = 0; i < n; ++i) {
        fz[i] = half_rho_cd * area[i] * std::abs(uz[i]) * uz[i];
        const double k = half_rho_clat * area[i] * std::sqrt(ux[i] * ux[i] + uy[i] * uy[i]);
        fx[i] = k * ux[i];
        fy[i] = k * uy[i];
    }
}

}  // namespace

Wrench WrenchModel::drag(Scratch& sc) const {
    const std::size_t n = planform_.size();
    const double* cx = planform_.x.data();
    const double* cy = planform_.y.data();
    const double* area = planform_.area.data();
    cell_drag(n, area, sc.ux.data(), sc.uy.data(), sc.uz.data(), half_rho_cd_, half_rho_clat_, sc.fx.data(),
              sc.fy.data(), sc.fz.data());
    double fx = 0, fy = 0, fz = 0, tx = 0, ty = 0, tz = 0;
    for (std::size_t i = 0; i < n; ++i) {
        fx += sc.fx[i];
        fy += sc.fy[i];
        fz += sc.fz[i];
        tx += cy[i] * sc.fz[i];
        ty -= cx[i] * sc.fz[i];
        tz += cx[i] * sc.fy[i] - cy[i] * sc.fx[i];
    }
    if (config_.sufferer.thrust_loss) {
        const std::size_t rotors = planform_.rotor_centre.size();
        for (std::size_t r = 0; r < rotors; ++r) {
            double inflow = 0;  // area-weighted downward flow through the disc
            for (std::size_t i = planform_.rotor_cells[r][0]; i < planform_.rotor_cells[r][1]; ++i)
                inflow += area[i] * sc.uz[i];
            const double dT = config_.sufferer.kv_omega_n_per_mps * inflow / planform_.rotor_area[r];
            fz += dT;
            tx += planform_.rotor_centre[r][1] * dT;
            ty -= planform_.rotor_centre[r][0] * dT;
        }
    }
    Wrench w;
    w << fx, fy, fz, tx, ty, tz;
    return w;
}

Wrench WrenchModel::beyond_the_jets(const Vec3& suf, std::span<const Producer> producers) const {
    Wrench w = Wrench::Zero();
    const AirScene scene{suf, producers};
    for (const auto* t : air_effects_) w += to_wrench(t->air_wrench(config_.effects, scene));
    return w + buffeting(suf, producers);
}

Wrench WrenchModel::buffeting(const Vec3& suf, std::span<const Producer> producers) const {
    // Each jet's turbulent lateral velocity, scaled by its local axial speed at each rotor, drives
    // that rotor's in-plane drag (H-force), which acts in the rotor plane: forces and yaw only.
    Wrench w = Wrench::Zero();
    const double c_h = config_.sufferer.rotor_drag_n_per_mps;
    if (c_h <= 0) return w;
    const auto& centres = planform_.rotor_centre;
    std::array<double, flight::kMaxRotors> cx{}, cy{};
    for (std::size_t r = 0; r < centres.size(); ++r) {
        cx[r] = centres[r][0];
        cy[r] = centres[r][1];
    }
    for (const auto& p : producers) {
        if (p.lateral_gust.isZero()) continue;
        std::array<double, flight::kMaxRotors> ux{}, uy{}, uz{};
        add_velocity(suf, cx.data(), cy.data(), centres.size(), p, 1.0, ux.data(), uy.data(), uz.data());
        for (std::size_t r = 0; r < centres.size(); ++r) {
            const double axial = ux[r] * p.axis.x() + uy[r] * p.axis.y() + uz[r] * p.axis.z();
            const double fx = c_h * axial * p.lateral_gust.x(), fy = c_h * axial * p.lateral_gust.y();
            w[0] += fx;
            w[1] += fy;
            w[5] += cx[r] * fy - cy[r] * fx;
        }
    }
    return w;
}

Wrench WrenchModel::buffeting_sigma(const Vec3& suf, std::span<const Producer> producers, double intensity) const {
    Wrench var = Wrench::Zero();
    for (const auto& p : producers) {
        for (const Vec3& g : {Vec3(intensity, 0, 0), Vec3(0, intensity, 0)}) {
            Producer one = p;
            one.lateral_gust = g - g.dot(p.axis) * p.axis;
            var += buffeting(suf, std::span<const Producer>(&one, 1)).cwiseAbs2();
        }
    }
    return var.cwiseSqrt();
}

Wrench WrenchModel::evaluate(const Vec3& suf, std::span<const Producer> producers) const {
    thread_local Scratch sc;
    const std::size_t k = producers.size();
    const bool sum = config_.aggregation == Aggregation::force_sum;
    Wrench total = beyond_the_jets(suf, producers);
    if (k == 0) return total;
    const std::size_t n = planform_.size();
    if (!sum) sc.reset(n);
    const auto add = [&](const Producer& p, double weight) {
        if (!sum) return add_velocity(suf, p, weight, sc);
        sc.reset(n);
        add_velocity(suf, p, 1.0, sc);
        total += weight == 1.0 ? drag(sc) : Wrench(weight * drag(sc));
    };
    if (!regrouper_ || k == 1) {  // the common case, without any allocation
        for (const auto& p : producers) add(p, 1.0);
    } else {
        thread_local std::vector<WeightedProducer> jets;
        jets.clear();
        regrouper_->regroup_jets(config_.effects, AirScene{suf, producers}, jets);
        for (const auto& j : jets) add(j.producer, j.weight);
    }
    if (!sum) total += drag(sc);
    return total;
}

Vec3 WrenchModel::air_velocity(const Vec3& point, std::span<const Producer> producers) const {
    const double zero = 0.0;
    double u[3] = {0, 0, 0};
    for (const auto& p : producers) add_velocity(point, &zero, &zero, 1, p, 1.0, &u[0], &u[1], &u[2]);
    return Vec3(u[0], u[1], u[2]);
}

}  // namespace dw::physics
