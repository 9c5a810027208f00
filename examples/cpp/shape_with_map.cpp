/*
 * Shapes joint moves of a UR e-Series arm from C++ with a map loaded from a map file, paper10
 * or modal (written by `tvist fit-map [--kind modal]`, DynamicMap.save or ModalMap.save),
 * through the header-only tvist.hpp.
 *
 *   shape_with_map ROBOT PAYLOAD_KG COM_X COM_Y COM_Z MAP_JSON DT_S SHAPER [IN OUT]
 *
 * Without IN/OUT it shapes a built-in move and checks that the shaped move ends where the
 * commanded one does (exit code 0) - what `make ffi-test` runs. With IN/OUT it reads rows of
 * joint positions (rad, whitespace separated, one sample per line; the first row is the rest
 * pose), shapes them and writes the shaped rows with 17 significant digits.
 *
 * Build (what `make ffi-test` does):
 *   c++ -std=c++17 -Wall -Wextra -Werror -Iinclude examples/cpp/shape_with_map.cpp \
 *       target/release/libtvist.a -lgcc_s -lutil -lrt -lpthread -lm -ldl -o shape_with_map
 */
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "tvist.hpp"

// The handle owns a C resource: it moves, never copies, and the per-cycle calls never throw.
static_assert(!std::is_copy_constructible_v<tvist::Shaper>, "move-only");
static_assert(std::is_nothrow_move_constructible_v<tvist::Shaper>, "noexcept move");
static_assert(noexcept(std::declval<tvist::Shaper &>().step(nullptr, nullptr)), "noexcept step");

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Setup {
    std::string robot;
    double payload_kg;
    std::array<double, 3> com_m;
    std::string map_path;
    double dt_s;
    std::string shaper;
};

int shape_files(tvist::Shaper &shaper, const std::string &in_path, const std::string &out_path) {
    std::ifstream in(in_path);
    std::ofstream out(out_path);
    if (!in || !out) {
        std::cerr << "cannot open " << (in ? out_path : in_path) << "\n";
        return 2;
    }
    const std::size_t n = shaper.n_dof();
    std::vector<double> q(n), q_out(n);
    std::string line;
    bool first = true;
    char text[32];
    while (std::getline(in, line)) {
        std::istringstream row(line);
        for (std::size_t j = 0; j < n; ++j) {
            if (!(row >> q[j])) {
                std::cerr << in_path << ": a row with fewer than " << n << " numbers\n";
                return 2;
            }
        }
        if (first) {
            shaper.reset(q.data());
            first = false;
        }
        const int32_t status = shaper.step(q.data(), q_out.data());
        if (status < 0) {
            std::cerr << "step failed with code " << status << "\n";
            return 1;
        }
        for (std::size_t j = 0; j < n; ++j) {
            std::snprintf(text, sizeof text, "%.17g", q_out[j]);
            out << text << (j + 1 < n ? " " : "\n");
        }
    }
    return 0;
}

int shape_builtin_move(tvist::Shaper shaper, double dt_s) {
    const std::size_t n = shaper.n_dof();
    std::vector<double> q_start(n, 0.0), q(n), q_out(n);
    q_start[1] = -kPi;
    q_start[3] = -kPi / 2.0;
    shaper.reset(q_start.data());
    const double move_s = 1.0, hold_s = 0.8;
    double max_lag = 0.0;
    const int samples = static_cast<int>((move_s + hold_s) / dt_s) + 1;
    for (int k = 0; k < samples; ++k) {
        const double tau = std::fmin(k * dt_s / move_s, 1.0);
        const double s = tau - std::sin(2.0 * kPi * tau) / (2.0 * kPi);
        for (std::size_t j = 0; j < n; ++j) q[j] = q_start[j] + (j < 3 ? 0.5 * s : 0.0);
        if (shaper.step(q.data(), q_out.data()) < 0) return 1;
        for (std::size_t j = 0; j < n; ++j) max_lag = std::fmax(max_lag, std::fabs(q_out[j] - q[j]));
    }
    // At rest after a standstill longer than the delay the output equals the input up to
    // rounding (a few ulp of ~3 rad); 1e-12 rad allows that and nothing else.
    bool ok = max_lag > 1e-3;
    for (std::size_t j = 0; j < n; ++j) ok = ok && std::fabs(q_out[j] - q[j]) <= 1e-12;
    const tvist::StatusCounts counts = shaper.status_counts();
    std::printf("delay at the end pose: %.1f ms, largest lag %.4f rad\n", 1e3 * shaper.delay_s(),
                max_lag);
    std::printf("cycles with held input %llu, held modes %llu, clamped delay %llu\n",
                static_cast<unsigned long long>(counts[0]),
                static_cast<unsigned long long>(counts[1]),
                static_cast<unsigned long long>(counts[2]));
    std::printf("%s\n", ok ? "ok: the shaped move ends where the commanded one does" : "FAILED");
    return ok ? 0 : 1;
}

}  // namespace

int main(int argc, char **argv) {
    if (argc != 9 && argc != 11) {
        std::cerr << "usage: " << argv[0]
                  << " ROBOT PAYLOAD_KG COM_X COM_Y COM_Z MAP_JSON DT_S SHAPER [IN OUT]\n";
        return 2;
    }
    const Setup setup{argv[1],
                      std::atof(argv[2]),
                      {std::atof(argv[3]), std::atof(argv[4]), std::atof(argv[5])},
                      argv[6],
                      std::atof(argv[7]),
                      argv[8]};
    try {
        tvist::Shaper shaper = tvist::Shaper::from_map(setup.robot, setup.payload_kg, setup.com_m,
                                                       setup.map_path, setup.dt_s, setup.shaper);
        if (argc == 11) return shape_files(shaper, argv[9], argv[10]);
        // Setup errors are exceptions: a map is refused for a robot it was not identified on.
        const char *other = setup.robot == "ur10e" ? "ur5e" : "ur10e";
        try {
            tvist::Shaper::from_map(other, setup.payload_kg, setup.com_m, setup.map_path,
                                    setup.dt_s, setup.shaper);
            std::printf("the map names no robot: accepted for %s too\n", other);
        } catch (const tvist::Error &e) {
            if (e.code() != TVIST_ERR_ROBOT_MISMATCH) throw;
            std::printf("refused for %s: %s\n", other, e.what());
        }
        return shape_builtin_move(std::move(shaper), setup.dt_s);
    } catch (const tvist::Error &e) {
        std::cerr << "tvist error " << e.code() << ": " << e.what() << "\n";
        return 1;
    }
}
