/*
 * tvist.hpp - header-only C++17 (and C++20) wrapper of the C API (tvist.h): an RAII, move-only shaper
 * handle. Setup errors throw tvist::Error (with the library's code and message); the
 * per-cycle calls are noexcept, allocation-free and return the status bits.
 *
 *   tvist::Shaper s = tvist::Shaper::from_map("ur10e", 5.0, {0, 0, 0.05}, "map.json", 0.002);
 *   s.reset(q0);
 *   int32_t status = s.step(q_planned, q_cmd);   // every cycle; q arrays of s.n_dof() doubles
 *
 * step and reset take raw pointers (n_dof() doubles), std::array<double, N>, std::vector<double>
 * and, in C++20, std::span; on a length other than n_dof() the sized forms return
 * TVIST_STATUS_BAD_LENGTH (step) or TVIST_ERR_DIMENSION_MISMATCH (reset).
 *
 * Link as for the C API (libtvist.a or libtvist.so).
 */
#ifndef TVIST_HPP
#define TVIST_HPP

#include <array>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>
#if __cplusplus >= 202002L
#include <span>
#endif

#include "tvist.h"

namespace tvist {

/* A setup error: code() is the TvistError, what() the library's message. */
class Error : public std::runtime_error {
public:
    Error(int32_t code, const std::string &message) : std::runtime_error(message), code_(code) {}
    int32_t code() const noexcept { return code_; }

private:
    int32_t code_;
};

/* Setup options (the defaults are those of the plain C constructors). */
struct Options {
    bool cubic_interpolation = false;  /* Lagrange order 3 instead of linear */
    double ei_tolerance = 0.0;         /* "ei" only; 0: the default 5 % */
    double safety_factor = 0.0;        /* delay-line margin; 0: the default 1.5 */
    bool allow_other_robot = false;    /* accept a map identified on another robot */

    TvistShaperOptions to_c() const noexcept {
        TvistShaperOptions o{};
        o.interpolation = cubic_interpolation ? TVIST_INTERP_CUBIC : TVIST_INTERP_LINEAR;
        o.ei_tolerance = ei_tolerance;
        o.safety_factor = safety_factor;
        o.allow_other_robot = allow_other_robot ? 1 : 0;
        return o;
    }
};

/* Per-flag counts of tvist_shaper_status_counts (index k counts bit 1 << k). */
using StatusCounts = std::array<uint64_t, TVIST_N_STATUS_FLAGS>;

/* One multi-mode FD-TVIST shaper. Move-only; the handle is freed by the destructor. */
class Shaper {
public:
    /* Fixed modes (wn_rad_s[m], zeta[m]) over n_dof channels. */
    static Shaper constant(const std::vector<double> &wn_rad_s, const std::vector<double> &zeta,
                           double dt_s, std::size_t n_dof, const std::string &shaper = "zv",
                           const Options &options = Options()) {
        if (wn_rad_s.size() != zeta.size()) {
            throw Error(TVIST_ERR_DIMENSION_MISMATCH, "wn_rad_s and zeta differ in length");
        }
        const TvistShaperOptions o = options.to_c();
        TvistShaper *out = nullptr;
        check(tvist_shaper_new_constant_ex(wn_rad_s.data(), zeta.data(), wn_rad_s.size(), dt_s,
                                           n_dof, shaper.c_str(), &o, &out));
        return Shaper(out);
    }

    /* The map in map_json_path (paper10 or modal map file) for robot `robot` (a UR name, see
     * TVIST_ERR_UNKNOWN_ROBOT, or a robot file *.json from `tvist robot-file`) with a point
     * payload. */
    static Shaper from_map(const std::string &robot, double payload_kg,
                           const std::array<double, 3> &payload_com_m,
                           const std::string &map_json_path, double dt_s,
                           const std::string &shaper = "zv", const Options &options = Options()) {
        const TvistShaperOptions o = options.to_c();
        TvistShaper *out = nullptr;
        check(tvist_shaper_new_map_ex(robot.c_str(), payload_kg, payload_com_m.data(),
                                      map_json_path.c_str(), dt_s, shaper.c_str(), &o, &out));
        return Shaper(out);
    }

    /* The paper's UR5e map ("ur5e" only). */
    static Shaper ur_map(const std::string &robot, double payload_kg,
                         const std::array<double, 3> &payload_com_m, double dt_s,
                         const std::string &shaper = "zv") {
        TvistShaper *out = nullptr;
        check(tvist_shaper_new_ur_map(robot.c_str(), payload_kg, payload_com_m.data(), dt_s,
                                      shaper.c_str(), &out));
        return Shaper(out);
    }

    Shaper(const Shaper &) = delete;
    Shaper &operator=(const Shaper &) = delete;
    Shaper(Shaper &&other) noexcept : handle_(std::exchange(other.handle_, nullptr)) {}
    Shaper &operator=(Shaper &&other) noexcept {
        if (this != &other) {
            tvist_shaper_free(handle_);
            handle_ = std::exchange(other.handle_, nullptr);
        }
        return *this;
    }
    ~Shaper() { tvist_shaper_free(handle_); }

    /* One cycle: q_in -> q_out, n_dof() doubles each (may be the same array). Returns the
     * TVIST_STATUS_* bits, or TVIST_ERR_NULL on a moved-from shaper. */
    int32_t step(const double *q_in, double *q_out) noexcept {
        return tvist_shaper_step(handle_, q_in, q_out, n_dof());
    }

    /* One cycle on containers that know their length (std::array<double, N>, std::vector;
     * std::span in C++20): TVIST_STATUS_BAD_LENGTH unless both hold n_dof() doubles. */
    template <std::size_t N>
    int32_t step(const std::array<double, N> &q_in, std::array<double, N> &q_out) noexcept {
        return tvist_shaper_step(handle_, q_in.data(), q_out.data(), N);
    }
    int32_t step(const std::vector<double> &q_in, std::vector<double> &q_out) noexcept {
        return step_n(q_in.data(), q_in.size(), q_out.data(), q_out.size());
    }

    /* Replaces the map by the map file map_json_path between moves (tvist_shaper_set_map):
     * TVIST_OK, or TVIST_ERR_MID_MOVE / a map-file code with the shaper unchanged. A setup
     * call: not from the control loop. */
    int32_t set_map(const std::string &map_json_path) noexcept {
        return tvist_shaper_set_map(handle_, map_json_path.c_str());
    }

    /* Shapes the n_modes lowest-frequency modes of the modal map between moves
     * (tvist_shaper_set_shaped_modes): TVIST_OK, or TVIST_ERR_MID_MOVE /
     * TVIST_ERR_INVALID_PARAMETER with the shaper unchanged. A setup call: not from the
     * control loop. */
    int32_t set_shaped_modes(std::size_t n_modes) noexcept {
        return tvist_shaper_set_shaped_modes(handle_, n_modes);
    }

    /* Holds the modes the map gives at the pose q (n_dof() doubles) from the next move on;
     * nullptr follows the pose again (tvist_shaper_hold_modes_at): TVIST_OK, or
     * TVIST_ERR_MID_MOVE / TVIST_ERR_INVALID_PARAMETER with the shaper unchanged. A setup
     * call: not from the control loop. */
    int32_t hold_modes_at(const double *q) noexcept {
        return tvist_shaper_hold_modes_at(handle_, q, n_dof());
    }

    /* At rest at q0 (n_dof() doubles). */
    int32_t reset(const double *q0) noexcept { return tvist_shaper_reset(handle_, q0, n_dof()); }

    /* At rest at q0 (a container of n_dof() doubles; TVIST_ERR_DIMENSION_MISMATCH otherwise). */
    template <std::size_t N>
    int32_t reset(const std::array<double, N> &q0) noexcept {
        return tvist_shaper_reset(handle_, q0.data(), N);
    }
    int32_t reset(const std::vector<double> &q0) noexcept {
        return tvist_shaper_reset(handle_, q0.data(), q0.size());
    }

#if __cplusplus >= 202002L
    int32_t step(std::span<const double> q_in, std::span<double> q_out) noexcept {
        return step_n(q_in.data(), q_in.size(), q_out.data(), q_out.size());
    }
    int32_t reset(std::span<const double> q0) noexcept {
        return tvist_shaper_reset(handle_, q0.data(), q0.size());
    }
#endif

    double delay_s() const noexcept { return tvist_shaper_delay_s(handle_); }
    std::size_t n_dof() const noexcept { return tvist_shaper_n_dof(handle_); }
    explicit operator bool() const noexcept { return handle_ != nullptr; }

    StatusCounts status_counts() const noexcept {
        StatusCounts counts{};
        tvist_shaper_status_counts(handle_, counts.data(), counts.size());
        return counts;
    }

    /* The C handle, for calls this wrapper does not cover (still owned by this object). */
    TvistShaper *get() const noexcept { return handle_; }

private:
    explicit Shaper(TvistShaper *handle) noexcept : handle_(handle) {}

    static std::string last_error() {
        std::string text(tvist_last_error_message(nullptr, 0) + 1, '\0');
        tvist_last_error_message(&text[0], text.size());
        text.pop_back();
        return text;
    }

    /* tvist_shaper_step on arrays of stated lengths. The library checks the length against
     * n_dof (TVIST_STATUS_BAD_LENGTH, counted, nothing accessed); arrays of two lengths are
     * passed as length 0 so that they get the same answer. */
    int32_t step_n(const double *q_in, std::size_t n_in, double *q_out,
                   std::size_t n_out) noexcept {
        return tvist_shaper_step(handle_, q_in, q_out, n_in == n_out ? n_in : 0);
    }

    static void check(int32_t code) {
        if (code != TVIST_OK) {
            throw Error(code, last_error());
        }
    }

    TvistShaper *handle_ = nullptr;
};

}  // namespace tvist

#endif /* TVIST_HPP */
