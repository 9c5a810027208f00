/*
 * tvist.hpp's step/reset on std::array, std::vector and (C++20) std::span shape exactly as the
 * raw-pointer forms, and refuse a container of the wrong length as the C API does. Built as
 * C++17 and as C++20 by `make cpp-containers`; prints "ok" and exits 0, or names the failure.
 */
#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

#include "tvist.hpp"

namespace {

constexpr std::size_t kDof = 6;
constexpr double kDtS = 0.002;

int failures = 0;

void expect(bool ok, const char *what) {
    if (!ok) {
        std::printf("FAILED: %s\n", what);
        ++failures;
    }
}

tvist::Shaper make_shaper() {
    // Two fixed modes, rad/s (about 8 and 12 Hz), as a UR arm's base and shoulder.
    return tvist::Shaper::constant({50.0, 75.0}, {0.05, 0.1}, kDtS, kDof);
}

/* Sample k of a 0.4 s ramp of every joint from 0 to 0.3 rad, then rest. */
double reference(int k, std::size_t j) {
    const double s = std::fmin(k * kDtS / 0.4, 1.0);
    return 0.3 * s * (1.0 + 0.1 * static_cast<double>(j));
}

}  // namespace

int main() {
    tvist::Shaper by_pointer = make_shaper(), by_array = make_shaper(), by_vector = make_shaper();
    const std::array<double, kDof> rest{};
    expect(by_pointer.reset(rest.data()) == TVIST_OK, "reset(pointer)");
    expect(by_array.reset(rest) == TVIST_OK, "reset(std::array)");
    expect(by_vector.reset(std::vector<double>(kDof, 0.0)) == TVIST_OK, "reset(std::vector)");
#if __cplusplus >= 202002L
    tvist::Shaper by_span = make_shaper();
    expect(by_span.reset(std::span<const double>(rest)) == TVIST_OK, "reset(std::span)");
#endif
    double moved = 0.0;
    for (int k = 0; k < 400; ++k) {
        std::array<double, kDof> q{}, out_pointer{}, out_array{};
        for (std::size_t j = 0; j < kDof; ++j) q[j] = reference(k, j);
        std::vector<double> q_vector(q.begin(), q.end()), out_vector(kDof);
        expect(by_pointer.step(q.data(), out_pointer.data()) >= 0, "step(pointer)");
        expect(by_array.step(q, out_array) >= 0, "step(std::array)");
        expect(by_vector.step(q_vector, out_vector) >= 0, "step(std::vector)");
        for (std::size_t j = 0; j < kDof; ++j) {
            // The same core call on the same numbers: equal to the last bit.
            expect(out_array[j] == out_pointer[j], "std::array output equals the pointer form");
            expect(out_vector[j] == out_pointer[j], "std::vector output equals the pointer form");
            moved = std::fmax(moved, std::fabs(out_pointer[j] - q[j]));
        }
#if __cplusplus >= 202002L
        std::array<double, kDof> out_span{};
        expect(by_span.step(std::span<const double>(q), std::span<double>(out_span)) >= 0,
               "step(std::span)");
        for (std::size_t j = 0; j < kDof; ++j) {
            expect(out_span[j] == out_pointer[j], "std::span output equals the pointer form");
        }
#endif
    }
    // A shaper that passed its input through would make the comparisons above trivial.
    expect(moved > 1e-3, "the move was shaped (output differs from input by > 1 mrad)");

    // Wrong lengths: refused with the C API's answers, nothing written.
    std::array<double, 3> short_q{}, short_out{9.0, 9.0, 9.0};
    expect(by_array.step(short_q, short_out) == TVIST_STATUS_BAD_LENGTH, "step(short std::array)");
    expect(short_out[0] == 9.0, "a refused step writes nothing");
    expect(by_array.reset(short_q) == TVIST_ERR_DIMENSION_MISMATCH, "reset(short std::array)");
    std::vector<double> q6(kDof, 0.0), out5(kDof - 1, 9.0);
    expect(by_vector.step(q6, out5) == TVIST_STATUS_BAD_LENGTH, "step(vectors of two lengths)");
    expect(out5[0] == 9.0, "a refused step writes nothing (vectors)");
    // Each refused step is counted once under TVIST_STATUS_BAD_LENGTH (1 << 4), as the C API does.
    expect(by_array.status_counts()[4] == 1, "one bad-length step counted (std::array)");
    expect(by_vector.status_counts()[4] == 1, "one bad-length step counted (vectors)");

    std::printf("%s (C++%ld)\n", failures == 0 ? "ok" : "FAILED", __cplusplus / 100 % 100);
    return failures == 0 ? 0 : 1;
}
