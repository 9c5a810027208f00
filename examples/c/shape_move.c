/*
 * Shapes a joint move of a UR5e with the paper's dynamic map at 500 Hz, from C.
 *
 * Build and run (what `make ffi-test` does):
 *   cargo build -p tvist-ffi --release
 *   cc -std=c11 -Wall -Wextra -Werror -Iinclude examples/c/shape_move.c \
 *      target/release/libtvist.a -lgcc_s -lutil -lrt -lpthread -lm -ldl -o shape_move
 *   ./shape_move
 *
 * Exit code 0 if the shaped move ends exactly where the commanded one does, 1 otherwise.
 */
#include <math.h>
#include <stdio.h>

#include "tvist.h"

#define N_DOF 6
#define DT_S 0.002         /* 500 Hz control period */
#define MOVE_S 1.2         /* duration of the commanded move */
#define HOLD_S 0.6         /* standstill after it: longer than any shaper delay here */
#define PI 3.14159265358979323846

/* Double-S-like position profile on [0, 1]: s = tau - sin(2 pi tau) / (2 pi) has zero
 * velocity and acceleration at both ends and a bounded jerk in between. */
static double smooth_fraction(double tau) {
    if (tau <= 0.0) return 0.0;
    if (tau >= 1.0) return 1.0;
    return tau - sin(2.0 * PI * tau) / (2.0 * PI);
}

static int report_error(const char *what, int32_t code) {
    char message[256];
    tvist_last_error_message(message, sizeof message);
    fprintf(stderr, "%s failed with code %d: %s\n", what, (int)code, message);
    return 1;
}

int main(void) {
    /* Start in the paper's pose Q1 (arm stretched out); move base, shoulder and elbow. */
    const double q_start[N_DOF] = {0.0, -PI, 0.0, -PI / 2.0, 0.0, 0.0};
    const double dq[N_DOF] = {0.6, 0.5, 0.8, 0.0, 0.0, 0.0};
    const double payload_com_m[3] = {0.0, 0.0, 0.05};
    TvistShaper *shaper = NULL;

    /* Error handling: a misspelt shaper name is reported, not guessed. */
    int32_t rc = tvist_shaper_new_ur_map("ur5e", 5.0, payload_com_m, DT_S, "zvv", &shaper);
    if (rc != TVIST_ERR_UNKNOWN_SHAPER || shaper != NULL) {
        fprintf(stderr, "expected TVIST_ERR_UNKNOWN_SHAPER, got %d\n", (int)rc);
        return 1;
    }

    rc = tvist_shaper_new_ur_map("ur5e", 5.0, payload_com_m, DT_S, "zv", &shaper);
    if (rc != TVIST_OK) return report_error("tvist_shaper_new_ur_map", rc);
    if (tvist_shaper_n_dof(shaper) != N_DOF) {
        fprintf(stderr, "expected %d joints\n", N_DOF);
        tvist_shaper_free(shaper);
        return 1;
    }

    const int n_samples = (int)((MOVE_S + HOLD_S) / DT_S) + 1;
    double q_in[N_DOF], q_out[N_DOF];
    double max_lag_rad = 0.0;
    int32_t status_union = 0;
    int failed = 0;

    for (int k = 0; k < n_samples; ++k) {
        const double s = smooth_fraction(k * DT_S / MOVE_S);
        for (int j = 0; j < N_DOF; ++j) q_in[j] = q_start[j] + s * dq[j];
        const int32_t status = tvist_shaper_step(shaper, q_in, q_out, N_DOF);
        if (status < 0) {
            fprintf(stderr, "step %d failed with code %d\n", k, (int)status);
            failed = 1;
            break;
        }
        status_union |= status;
        if (k == 0) printf("delay at the start pose: %.1f ms\n", 1e3 * tvist_shaper_delay_s(shaper));
        for (int j = 0; j < N_DOF; ++j) {
            const double lag = fabs(q_out[j] - q_in[j]);
            if (lag > max_lag_rad) max_lag_rad = lag;
        }
    }
    printf("delay at the end pose:   %.1f ms\n", 1e3 * tvist_shaper_delay_s(shaper));
    printf("largest |shaped - commanded| during the move: %.4f rad\n", max_lag_rad);
    printf("status bits seen: %d\n", (int)status_union);

    /* After a standstill longer than the delay, every delayed sample equals the final input
     * and the impulse amplitudes sum to 1, so the output equals the input up to rounding
     * (a few ulp of ~3 rad, about 1e-15 rad); 1e-12 rad leaves room for that and nothing else. */
    for (int j = 0; j < N_DOF; ++j) {
        const double error = fabs(q_out[j] - q_in[j]);
        printf("joint %d: commanded %+.6f rad, shaped %+.6f rad\n", j, q_in[j], q_out[j]);
        if (!(error <= 1e-12)) failed = 1;
    }
    /* A filter that passed its input through would trivially end in place: require that the
     * shaper actually delayed the move (a 0.5 rad/s motion delayed by tens of ms lags >1e-3). */
    if (!(max_lag_rad > 1e-3)) failed = 1;
    if (status_union & (TVIST_STATUS_BAD_LENGTH | TVIST_STATUS_MODES_HELD)) failed = 1;

    tvist_shaper_free(shaper);
    printf("%s\n", failed ? "FAILED" : "ok: the shaped move ends where the commanded one does");
    return failed ? 1 : 0;
}
