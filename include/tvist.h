/*
 * tvist.h - C API of tvist: real-time time-varying multi-mode input shaping (FD-TVIST).
 *
 * Build the library with `cargo build -p tvist-ffi --release`, then link
 *   target/release/libtvist.a  (static: add -lgcc_s -lutil -lrt -lpthread -lm -ldl)  or
 *   target/release/libtvist.so (shared).
 *
 * Conventions: SI units (dt_s in s, wn_rad_s in rad/s, payload_kg in kg, payload_com_m in m);
 * joint arrays hold n_dof doubles. Setup calls return TVIST_OK (0) or a negative TvistError;
 * tvist_shaper_step returns the status bits (>= 0) of the cycle or a negative TvistError.
 * No call unwinds or aborts on bad input: null or misaligned pointers and wrong lengths give
 * an error code. An array shorter than its stated length, a freed handle or a string without
 * its NUL remain undefined behaviour, as in any C API.
 *
 * Threads: a handle may move between threads but must not be used by two at once.
 * Real time: tvist_shaper_step never allocates, locks or blocks; create handles at setup.
 */
#ifndef TVIST_H
#define TVIST_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Error codes (negative) returned by setup calls and by tvist_shaper_step / _reset. */
typedef enum TvistError {
    TVIST_OK = 0,
    /* A required pointer is null or not aligned for its type. */
    TVIST_ERR_NULL = -1,
    /* The shaper name is not one of "zv", "zvd", "zvdd", "mzv", "ei", "2hump_ei", "3hump_ei". */
    TVIST_ERR_UNKNOWN_SHAPER = -2,
    /* A parameter outside its domain (dt_s <= 0, n_dof == 0 or > TVIST_MAX_DOF, no modes,
     * a payload that is not physical, a damping ratio beyond the shaper's range, ...). */
    TVIST_ERR_INVALID_PARAMETER = -3,
    /* A mode (wn_rad_s, zeta) that is not finite, has wn_rad_s <= 0 or zeta outside [0, 1). */
    TVIST_ERR_INVALID_MODE = -4,
    /* An array length that does not match the shaper (n_dof of tvist_shaper_reset). */
    TVIST_ERR_DIMENSION_MISMATCH = -5,
    /* A robot name not in the robot data (e-Series "ur3e", "ur5e", "ur10e", "ur16e", "ur20";
     * CB-series "ur3", "ur5", "ur10") nor a readable, valid robot file (*.json), or not
     * "ur5e" for tvist_shaper_new_ur_map (the paper's map). */
    TVIST_ERR_UNKNOWN_ROBOT = -6,
    /* An internal error was caught at the boundary (a bug). Only free the handle after it. */
    TVIST_ERR_INTERNAL = -7,
    /* A map file that cannot be read or is not a valid map: not a physical map, more than
     * TVIST_MAX_MODES modes, longer than 1 MiB, a repeated key (the message names the field). */
    TVIST_ERR_MAP_FILE = -8,
    /* A map identified on another robot than the one named (the message names both). */
    TVIST_ERR_ROBOT_MISMATCH = -9,
    /* A request beyond a setup limit (TVIST_MAX_DOF channels, TVIST_MAX_MODES modes,
     * TVIST_MAX_DELAY_LINE_BYTES of delay lines): refused before anything is allocated. */
    TVIST_ERR_TOO_LARGE = -10,
    /* tvist_shaper_set_map, tvist_shaper_set_shaped_modes or tvist_shaper_hold_modes_at on a
     * shaper mid-move (its delay lines not at rest on the input). */
    TVIST_ERR_MID_MOVE = -11
} TvistError;

/* Status bits of one cycle (tvist_shaper_step >= 0); 0 is a clean cycle. */
/* A non-finite input sample was replaced by the last valid one. */
#define TVIST_STATUS_INPUT_HELD 1
/* The dynamics provider returned an invalid mode; the last valid mode was used. */
#define TVIST_STATUS_MODES_HELD 2
/* A delay exceeded the delay-line capacity and was clamped to it. */
#define TVIST_STATUS_DELAY_CLAMPED 4
/* No valid mode seen yet for some filter: it passed its input through unshaped. */
#define TVIST_STATUS_UNSHAPED 8
/* n_dof differs from the shaper's: nothing was read or written. */
#define TVIST_STATUS_BAD_LENGTH 16
/* A damping ratio beyond the shaper's published range; designed at that limit. */
#define TVIST_STATUS_ZETA_CLAMPED 32
/* A mode at or above the Nyquist frequency (wn_rad_s >= pi / dt_s): it cannot be cancelled at
 * this rate. Shaped as given (impulses within one sample, a sub-sample smoothing). */
#define TVIST_STATUS_MODE_ABOVE_NYQUIST 64
/* A mode changed faster than a slowly varying mode can (its natural frequency by more than
 * 5/s in ln wn, i.e. 1 % per 2 ms cycle, or its damping ratio by more than 5/s): the provider's
 * mode jumped (e.g. a map that switched eigenmodes) and the filter approached it at that limit
 * instead, so that the shaped reference gets no step. */
#define TVIST_STATUS_MODE_SLEW_LIMITED 128
/* Number of status flags: flag k is bit (1 << k) (tvist_shaper_status_counts). */
#define TVIST_N_STATUS_FLAGS 8

/* Largest number of joint channels of a handle. */
#define TVIST_MAX_DOF 4096
/* Largest number of modes of a shaper: tvist_shaper_new_constant (more: TVIST_ERR_TOO_LARGE)
 * and a map file (more: TVIST_ERR_MAP_FILE naming "modes"). */
#define TVIST_MAX_MODES 64
/* Largest total size of a handle's delay lines in bytes (256 MiB): a larger request (many
 * channels, a very slow mode, a very short dt_s) returns TVIST_ERR_TOO_LARGE. */
#define TVIST_MAX_DELAY_LINE_BYTES 268435456

/* TvistShaperOptions.interpolation: fractional delays by Lagrange order 1 or 3. */
#define TVIST_INTERP_LINEAR 0
#define TVIST_INTERP_CUBIC 1

/* Options of the _ex constructors. A zero-initialized struct ({0}) holds the defaults. */
typedef struct TvistShaperOptions {
    /* TVIST_INTERP_LINEAR (default) or TVIST_INTERP_CUBIC. */
    int32_t interpolation;
    /* Vibration tolerance of the "ei" shaper (fraction, e.g. 0.05); 0: the default 5 %.
     * A nonzero value with another shaper is TVIST_ERR_INVALID_PARAMETER. */
    double ei_tolerance;
    /* Delay-line length over the longest expected shaper (>= 1); 0: the default 1.5. */
    double safety_factor;
    /* Nonzero: accept a map identified on another robot (research use). */
    int32_t allow_other_robot;
} TvistShaperOptions;

/* Opaque shaper handle. */
typedef struct TvistShaper TvistShaper;

/*
 * Shaper for n_modes fixed modes (wn_rad_s[m], zeta[m]): one cascaded filter per mode over
 * n_dof channels sampled every dt_s seconds, shaper family shaper_name. Linear interpolation;
 * delay lines sized 1.5 x the longest shaper. On success *out holds a new handle; on failure
 * *out is NULL (when out is usable) and tvist_last_error_message says why.
 */
int32_t tvist_shaper_new_constant(const double *wn_rad_s, const double *zeta, size_t n_modes,
                                  double dt_s, size_t n_dof, const char *shaper_name,
                                  TvistShaper **out);

/* tvist_shaper_new_constant with options (NULL: the defaults). */
int32_t tvist_shaper_new_constant_ex(const double *wn_rad_s, const double *zeta, size_t n_modes,
                                     double dt_s, size_t n_dof, const char *shaper_name,
                                     const TvistShaperOptions *options, TvistShaper **out);

/*
 * Shaper driven by the paper's UR5e dynamic map (base and shoulder modes, re-evaluated every
 * cycle at the previous shaped output) with the UR5e rigid-body model and a point payload of
 * payload_kg at payload_com_m (flange frame, m). robot_name must be "ur5e"; n_dof is 6.
 * Setup samples the workspace to validate the map (a few milliseconds).
 */
int32_t tvist_shaper_new_ur_map(const char *robot_name, double payload_kg,
                                const double payload_com_m[3], double dt_s,
                                const char *shaper_name, TvistShaper **out);

/*
 * Shaper driven by the map in file map_json_path (any map file tvist writes:
 * `tvist fit-map`, DynamicMap.save, ModalMap.save; a "kind": "modal" file solves the
 * mass-matrix eigenproblem of its flexible joints every cycle) for robot `robot`: a UR name
 * (e-Series "ur3e", "ur5e", "ur10e", "ur16e", "ur20" or CB-series "ur3", "ur5", "ur10") or
 * the path of a robot file ending in ".json" (one robot, as `tvist robot-file` writes it from
 * a URDF), with a point payload of payload_kg at payload_com_m (flange frame, m); shapes the
 * robot's joints (all of them) sampled every dt_s seconds. The map must have been identified
 * on that robot (TVIST_ERR_ROBOT_MISMATCH otherwise; see allow_other_robot of the _ex form).
 * TVIST_ERR_MAP_FILE for a file that cannot be read or is not a valid map (the message names
 * the file and the field). Setup reads the file and samples the workspace (milliseconds).
 */
int32_t tvist_shaper_new_map(const char *robot, double payload_kg, const double payload_com_m[3],
                             const char *map_json_path, double dt_s, const char *shaper,
                             TvistShaper **out);

/* tvist_shaper_new_map with options (NULL: the defaults). */
int32_t tvist_shaper_new_map_ex(const char *robot, double payload_kg,
                                const double payload_com_m[3], const char *map_json_path,
                                double dt_s, const char *shaper,
                                const TvistShaperOptions *options, TvistShaper **out);

/*
 * Replaces the map of a map-driven shaper by the map in map_json_path (validated as
 * tvist_shaper_new_map does), keeping its robot, payload, shaper, dt_s and options. A setup
 * call (reads the file, allocates): never from the control loop. Only between moves: the
 * shaper has not started, or its input has not changed for longer than the longest delay it
 * can read (every delay line holds one value per channel); the next move is then shaped
 * exactly as by a new shaper built from that file. TVIST_ERR_MID_MOVE mid-move,
 * TVIST_ERR_INVALID_PARAMETER for constant modes, the tvist_shaper_new_map codes for a bad
 * file; the shaper is unchanged on every error.
 */
int32_t tvist_shaper_set_map(TvistShaper *shaper, const char *map_json_path);

/*
 * Shapes the n_modes lowest-frequency modes of the shaper's modal map from the next move on
 * (frequency-ranked, as "shaped_modes": n_modes in a map file, whatever the map shaped
 * before), one cascaded filter each: the added delay is that of those modes.
 * 1 <= n_modes <= the map's number of flexible joints. A setup call (builds a new provider and
 * delay lines): never from the control loop. Only between moves, as tvist_shaper_set_map.
 * TVIST_ERR_MID_MOVE mid-move, TVIST_ERR_INVALID_PARAMETER for a shaper not driven by a modal
 * map or n_modes out of range; the shaper is unchanged on every error.
 */
int32_t tvist_shaper_set_shaped_modes(TvistShaper *shaper, size_t n_modes);

/*
 * Shapes from the next move on with the modes the shaper's map gives at the pose q (n_dof
 * doubles, rad), held constant instead of followed cycle by cycle; q NULL follows the pose of
 * every cycle again. For a move whose time-varying shaping leaves more ringing than its stop
 * pose's modes do: pass the move's end pose. tvist_shaper_set_map and
 * tvist_shaper_set_shaped_modes also end a hold. A setup call: never from the control loop.
 * Only between moves, as tvist_shaper_set_map. TVIST_ERR_MID_MOVE mid-move,
 * TVIST_ERR_DIMENSION_MISMATCH for another n_dof, TVIST_ERR_INVALID_PARAMETER for a shaper
 * not driven by a map or a pose where the map gives an invalid mode; the shaper is unchanged
 * on every error.
 */
int32_t tvist_shaper_hold_modes_at(TvistShaper *shaper, const double *q, size_t n_dof);

/*
 * One control cycle: shapes q_in into q_out (n_dof doubles each; they may be the same array).
 * Returns the TVIST_STATUS_* bits of the cycle (TVIST_STATUS_BAD_LENGTH if n_dof is wrong)
 * or TVIST_ERR_NULL. Allocation-free.
 */
int32_t tvist_shaper_step(TvistShaper *shaper, const double *q_in, double *q_out, size_t n_dof);

/*
 * Puts the shaper at rest at q0 (n_dof doubles; non-finite entries taken as 0): a following
 * constant input q0 passes unchanged. Returns TVIST_OK, TVIST_ERR_NULL or
 * TVIST_ERR_DIMENSION_MISMATCH.
 */
int32_t tvist_shaper_reset(TvistShaper *shaper, const double *q0, size_t n_dof);

/* Total delay of the latest cycle, s (0 before the first step; NaN for NULL). */
double tvist_shaper_delay_s(const TvistShaper *shaper);

/* Number of joint channels (0 for NULL). */
size_t tvist_shaper_n_dof(const TvistShaper *shaper);

/*
 * Per-flag status counts since construction: counts[k] is the number of tvist_shaper_step
 * calls whose status had bit (1 << k) set. Writes min(len, TVIST_N_STATUS_FLAGS) entries and
 * returns TVIST_N_STATUS_FLAGS (0 for NULL). Allocation-free.
 */
size_t tvist_shaper_status_counts(const TvistShaper *shaper, uint64_t *counts, size_t len);

/* Frees a handle; NULL is ignored. */
void tvist_shaper_free(TvistShaper *shaper);

/*
 * Copies this thread's last setup-error text into buf (len bytes, NUL-terminated when
 * len > 0, truncated if needed) and returns the text's full length without the NUL, like
 * snprintf. buf may be NULL when len is 0.
 */
size_t tvist_last_error_message(char *buf, size_t len);

#ifdef __cplusplus
}
#endif

#endif /* TVIST_H */
