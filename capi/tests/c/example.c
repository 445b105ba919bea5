/*
 * A C program against the aacmm C API: the demo of every function, and the
 * program the Rust test `c_example` compiles (with the system C compiler,
 * against include/aacmm.h and the built library), runs and checks.
 *
 *   example ARM.toml POSES.csv LENGTHS.csv
 *
 * It prints one tagged line per result; doubles are printed as the 16 hex
 * digits of their bits, so that the test can compare them with the Rust
 * API bit for bit:
 *
 *   version, arm_params, q, positions, jac_positions, jacobians,
 *   joint_q, joint_p, joint_jac, nominal_positions, error, files_params,
 *   files_sigmas, files_fixed, files_summary, verdict (`usable` or
 *   `refused`, then the reasons), verdict_notes, report (these three with
 *   newlines and backslashes escaped as \\n and \\\\), arrays_params,
 *   calibrated_positions, tracker_q, tracker_xyz, tracker_params,
 *   tracker_frames (the count), frame_NAME (per fitted frame: rotation,
 *   translation, their sigmas, the rotation matrix), tracker_auxiliary (the
 *   count of auxiliary columns), aux_NAME (per column: start, calibrated,
 *   sigma, and 1 or 0 for held or fitted), map (the calibration's
 *   uncertainty map: coverage, k_isotropic, rms, median, max), map_counts
 *   (its poses and bands), map_region_K (per band: reach from, to, poses,
 *   rms, max), sixd_quaternions (the tool poses' orientations, w x y z per
 *   row), sixd_auxiliary (the count of auxiliary columns of their fit),
 *   aux6_NAME (per column, as aux_NAME)
 *
 * Its own checks (expected error codes, arrays == files) make it exit with
 * status 1 and a message on stderr when they fail.
 */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "aacmm.h"

#define PI 3.14159265358979323846
#define POSES 13 /* not a multiple of the kernel's 4 lanes: the tail runs too */
#define TRACKED 40 /* tracker positions per station */

static int failures = 0;

static void fail(const char *what) {
    char message[512];
    aacmm_last_error_message(message, sizeof message);
    fprintf(stderr, "example: %s (last error: %s)\n", what, message);
    failures++;
}

/* Stops on an unexpected status: nothing after it would make sense. */
static void ok(AacmmStatus status, const char *what) {
    if (status != AACMM_STATUS_OK) {
        char message[512];
        aacmm_last_error_message(message, sizeof message);
        fprintf(stderr, "example: %s failed with status %d: %s\n", what, (int)status, message);
        exit(1);
    }
}

static void print_bits(const char *tag, const double *v, size_t n) {
    printf("%s", tag);
    for (size_t i = 0; i < n; i++) {
        uint64_t bits;
        memcpy(&bits, &v[i], sizeof bits);
        printf(" %016" PRIx64, bits);
    }
    printf("\n");
}

/* An error path: prints `error NAME CODE MESSAGE` and checks the code. */
static void expect(AacmmStatus got, AacmmStatus want, const char *name) {
    char message[512];
    aacmm_last_error_message(message, sizeof message);
    printf("error %s %d %s\n", name, (int)got, message);
    if (got != want) {
        fprintf(stderr, "example: %s gave status %d, expected %d\n", name, (int)got, (int)want);
        failures++;
    }
}

/* Prints `tag text` on one line: newlines and backslashes escaped (the test
 * undoes it). */
static void print_escaped(const char *tag, const char *text) {
    printf("%s ", tag);
    for (const char *c = text; *c; c++) {
        if (*c == '\n') {
            printf("\\n");
        } else if (*c == '\\') {
            printf("\\\\");
        } else {
            putchar(*c);
        }
    }
    printf("\n");
}

/* A string output of the API (report, verdict): asks for the length, then
 * copies into a buffer of that size. The caller frees it. */
static char *string_of(AacmmStatus (*get)(const AacmmCalibration *, char *, size_t, size_t *),
                       const AacmmCalibration *cal, const char *what) {
    size_t len = 0;
    AacmmStatus sized = get(cal, NULL, 0, &len);
    if (sized != AACMM_STATUS_BUFFER_TOO_SMALL) {
        fprintf(stderr, "example: %s: asking the length gave status %d\n", what, (int)sized);
        exit(1);
    }
    char *text = malloc(len + 1);
    ok(get(cal, text, len + 1, &len), what);
    return text;
}

/* ---- a small reader for the CSV files (what a host program has anyway) ---- */

#define MAX_TOUCHES 4096
#define MAX_POINTS 256
#define MAX_LENGTHS 256

static char labels[MAX_POINTS][64];
static size_t label_count = 0;

static uint32_t point_id(const char *label) {
    for (size_t i = 0; i < label_count; i++) {
        if (strcmp(labels[i], label) == 0) {
            return (uint32_t)i;
        }
    }
    if (label_count == MAX_POINTS) {
        fprintf(stderr, "example: too many points\n");
        exit(1);
    }
    snprintf(labels[label_count], sizeof labels[0], "%s", label);
    return (uint32_t)label_count++;
}

/* Splits a line at commas in place; returns the number of fields. */
static size_t split(char *line, char **fields, size_t max) {
    size_t n = 0;
    line[strcspn(line, "\r\n")] = '\0';
    for (char *f = line; n < max;) {
        fields[n++] = f;
        char *comma = strchr(f, ',');
        if (comma == NULL) {
            break;
        }
        *comma = '\0';
        f = comma + 1;
    }
    return n;
}

/* Poses file `point,q1,...,qn` in degrees → readings in rad and point ids. */
static size_t read_poses(const char *path, size_t joints, double *q, uint32_t *points) {
    FILE *f = fopen(path, "r");
    char line[1024];
    char *fields[16];
    size_t n = 0;
    int header = 1;
    if (f == NULL) {
        perror(path);
        exit(1);
    }
    while (fgets(line, sizeof line, f) != NULL) {
        if (line[0] == '#' || line[0] == '\n') {
            continue;
        }
        if (header) {
            header = 0;
            continue;
        }
        if (split(line, fields, 16) != joints + 1 || n == MAX_TOUCHES) {
            fprintf(stderr, "example: %s: unexpected row\n", path);
            exit(1);
        }
        points[n] = point_id(fields[0]);
        for (size_t j = 0; j < joints; j++) {
            /* The toolkit's degrees → radians: x · (π / 180). */
            q[n * joints + j] = strtod(fields[1 + j], NULL) * (PI / 180.0);
        }
        n++;
    }
    fclose(f);
    return n;
}

/* Lengths file `point_a,point_b,distance[,uncertainty]`. */
static size_t read_lengths(const char *path, AacmmReferenceLength *lengths) {
    FILE *f = fopen(path, "r");
    char line[1024];
    char *fields[8];
    size_t n = 0;
    int header = 1;
    if (f == NULL) {
        perror(path);
        exit(1);
    }
    while (fgets(line, sizeof line, f) != NULL) {
        if (line[0] == '#' || line[0] == '\n') {
            continue;
        }
        if (header) {
            header = 0;
            continue;
        }
        size_t k = split(line, fields, 8);
        if (k < 3 || n == MAX_LENGTHS) {
            fprintf(stderr, "example: %s: unexpected row\n", path);
            exit(1);
        }
        lengths[n].point_a = point_id(fields[0]);
        lengths[n].point_b = point_id(fields[1]);
        lengths[n].distance_mm = strtod(fields[2], NULL);
        lengths[n].uncertainty_mm = (k > 3 && fields[3][0] != '\0') ? strtod(fields[3], NULL) : NAN;
        n++;
    }
    fclose(f);
    return n;
}

/* ---- the program ---- */

/* Prints the count of `c`'s auxiliary columns under `count_tag`, then per
 * column `PREFIXNAME`: start, calibrated, sigma, and 1 or 0 for held or
 * fitted; returns the count. */
static size_t print_auxiliary(const AacmmCalibration *c, const char *count_tag,
                              const char *prefix) {
    size_t aux_count = 0, name_len = 0;
    ok(aacmm_calibration_auxiliary_count(c, &aux_count), "aacmm_calibration_auxiliary_count");
    printf("%s %zu\n", count_tag, aux_count);
    for (size_t k = 0; k < aux_count; k++) {
        AacmmAuxiliary column;
        char name[32], tag[48];
        ok(aacmm_calibration_auxiliary(c, k, &column, name, sizeof name, &name_len),
           "aacmm_calibration_auxiliary");
        snprintf(tag, sizeof tag, "%s%s", prefix, name);
        const double values[4] = {column.start, column.calibrated, column.sigma,
                                  column.fixed ? 1.0 : 0.0};
        print_bits(tag, values, 4);
    }
    return aux_count;
}

/* r = a·b, 3 × 3 row-major. */
static void mat_mul(const double a[9], const double b[9], double r[9]) {
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            r[3 * i + j] = 0;
            for (int k = 0; k < 3; k++) {
                r[3 * i + j] += a[3 * i + k] * b[3 * k + j];
            }
        }
    }
}

/* A turn by `t` rad about the axis `axis` (0 = x, 2 = z), row-major. */
static void turn_about(int axis, double t, double r[9]) {
    const double c = cos(t), s = sin(t);
    if (axis == 0) {
        const double m[9] = {1, 0, 0, 0, c, -s, 0, s, c};
        memcpy(r, m, sizeof m);
    } else {
        const double m[9] = {c, -s, 0, s, c, 0, 0, 0, 1};
        memcpy(r, m, sizeof m);
    }
}

/* The unit quaternion w, x, y, z of the rotation `r` (row-major). */
static void quaternion_of(const double r[9], double q[4]) {
    const double tr = r[0] + r[4] + r[8];
    if (tr > 0) {
        const double s = 2 * sqrt(tr + 1);
        q[0] = s / 4;
        q[1] = (r[7] - r[5]) / s;
        q[2] = (r[2] - r[6]) / s;
        q[3] = (r[3] - r[1]) / s;
    } else if (r[0] > r[4] && r[0] > r[8]) {
        const double s = 2 * sqrt(1 + r[0] - r[4] - r[8]);
        q[0] = (r[7] - r[5]) / s;
        q[1] = s / 4;
        q[2] = (r[1] + r[3]) / s;
        q[3] = (r[2] + r[6]) / s;
    } else if (r[4] > r[8]) {
        const double s = 2 * sqrt(1 + r[4] - r[0] - r[8]);
        q[0] = (r[2] - r[6]) / s;
        q[1] = (r[1] + r[3]) / s;
        q[2] = s / 4;
        q[3] = (r[5] + r[7]) / s;
    } else {
        const double s = 2 * sqrt(1 + r[8] - r[0] - r[4]);
        q[0] = (r[3] - r[1]) / s;
        q[1] = (r[2] + r[6]) / s;
        q[2] = (r[5] + r[7]) / s;
        q[3] = s / 4;
    }
}

/* Tool poses: the tracker's positions (`tq`, `txyz`, `tframes` of the
 * paper's nominal arm `made`, its twists ∓90°, no zero offsets) with the
 * orientation of a 6-D target mounted on the flange turned by 0.3 rad
 * about z then 0.2 rad about x, seen from each station (turned by `turn`
 * about z); row 5's target lost its lock (four NAN). Bad quaternions are
 * refused; the calibration fits the mount (three more auxiliary columns,
 * `mount.rx` …), printed as sixd_auxiliary and aux6_NAME. */
static void tool_poses(const AacmmArm *made, const double *tq, const double *txyz,
                       const uint32_t *tframes, const char **stations, const double *turn) {
    static double quats[2 * TRACKED * 4];
    double mount[9], mz[9], mx[9];
    turn_about(2, 0.3, mz);
    turn_about(0, 0.2, mx);
    mat_mul(mz, mx, mount);
    for (size_t i = 0; i < 2 * TRACKED; i++) {
        double r[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, link[9], z[9], x[9], next[9];
        for (size_t j = 0; j < 6; j++) {
            turn_about(2, tq[6 * i + j], z);
            turn_about(0, (j % 2 == 0 ? -1 : 1) * PI / 2, x);
            mat_mul(z, x, link);
            mat_mul(r, link, next);
            memcpy(r, next, sizeof next);
        }
        double station[9], seen[9];
        turn_about(2, turn[tframes[i]], station);
        mat_mul(station, r, next);
        mat_mul(next, mount, seen);
        quaternion_of(seen, quats + 4 * i);
    }
    for (size_t k = 0; k < 4; k++) {
        quats[4 * 5 + k] = NAN;
    }
    print_bits("sixd_quaternions", quats, 2 * TRACKED * 4);
    AacmmCalibrateOptions *sixd = NULL;
    ok(aacmm_calibrate_options_new(&sixd), "aacmm_calibrate_options_new");
    ok(aacmm_calibrate_options_set_method(sixd, AACMM_METHOD_LM),
       "aacmm_calibrate_options_set_method");
    ok(aacmm_calibrate_options_set_position_noise_mm(sixd, 0.015, 0.006),
       "aacmm_calibrate_options_set_position_noise_mm");
    ok(aacmm_calibrate_options_set_orientation_noise_rad(sixd, 0.01 * PI / 180),
       "aacmm_calibrate_options_set_orientation_noise_rad");
    /* Orientations need positions set as arrays first. */
    expect(aacmm_calibrate_options_set_position_orientations(sixd, quats, 2 * TRACKED * 4),
           AACMM_STATUS_INVALID_ARGUMENT, "orientations_without_positions");
    ok(aacmm_calibrate_options_set_positions(sixd, 6, tq, 2 * TRACKED * 6, txyz,
                                             2 * TRACKED * 3, tframes, 2 * TRACKED, stations, 2,
                                             NULL, 0),
       "aacmm_calibrate_options_set_positions");
    expect(aacmm_calibrate_options_set_position_orientations(sixd, quats, 2 * TRACKED * 4 - 4),
           AACMM_STATUS_LENGTH, "orientations_length");
    const double w = quats[0];
    quats[0] = 1.01 * w;
    expect(aacmm_calibrate_options_set_position_orientations(sixd, quats, 2 * TRACKED * 4),
           AACMM_STATUS_INPUT, "orientation_not_unit");
    quats[0] = w;
    quats[4 * 5] = 0.5; /* a row with some of its four NAN */
    expect(aacmm_calibrate_options_set_position_orientations(sixd, quats, 2 * TRACKED * 4),
           AACMM_STATUS_INPUT, "orientation_partly_nan");
    quats[4 * 5] = NAN;
    ok(aacmm_calibrate_options_set_position_orientations(sixd, quats, 2 * TRACKED * 4),
       "aacmm_calibrate_options_set_position_orientations");
    AacmmCalibration *posed = NULL;
    ok(aacmm_calibrate(made, NULL, 0, NULL, 0, NULL, 0, sixd, &posed),
       "aacmm_calibrate (tool poses)");
    print_auxiliary(posed, "sixd_auxiliary", "aux6_");
    aacmm_calibration_free(posed);
    aacmm_calibrate_options_free(sixd);
}

int main(int argc, char **argv) {
    if (argc != 4) {
        fprintf(stderr, "usage: %s ARM.toml POSES.csv LENGTHS.csv\n", argv[0]);
        return 2;
    }
    const char *arm_path = argv[1], *poses_path = argv[2], *lengths_path = argv[3];
    printf("version %s\n", aacmm_version());

    /* An arm from its file. */
    AacmmArm *arm = NULL;
    size_t joints = 0;
    ok(aacmm_arm_from_file(arm_path, &arm), "aacmm_arm_from_file");
    ok(aacmm_arm_joints(arm, &joints), "aacmm_arm_joints");
    const size_t n_params = aacmm_param_count(joints);
    double params[31];
    ok(aacmm_arm_params(arm, params, n_params), "aacmm_arm_params");
    print_bits("arm_params", params, n_params);

    /* Positions and Jacobians of a batch of poses. */
    static double q[POSES * 7], p[POSES * 3], p2[POSES * 3], jac[POSES * 3 * 31];
    for (size_t i = 0; i < POSES * joints; i++) {
        q[i] = 3.0 * sin(0.37 * (double)i + 0.1);
    }
    print_bits("q", q, POSES * joints);
    ok(aacmm_positions(arm, q, POSES * joints, p, POSES * 3), "aacmm_positions");
    print_bits("positions", p, POSES * 3);
    ok(aacmm_jacobians(arm, q, POSES * joints, p2, POSES * 3, jac, POSES * 3 * n_params),
       "aacmm_jacobians");
    print_bits("jac_positions", p2, POSES * 3);
    print_bits("jacobians", jac, POSES * 3 * n_params);

    /* The joint Jacobian of one pose. */
    double jp[3], jq[3 * 7];
    ok(aacmm_joint_jacobian(arm, q + 5 * joints, joints, jp, 3, jq, 3 * joints),
       "aacmm_joint_jacobian");
    print_bits("joint_q", q + 5 * joints, joints);
    print_bits("joint_p", jp, 3);
    print_bits("joint_jac", jq, 3 * joints);

    /* An arm from its parameters: the paper's nominal arm, mm and rad. */
    const double h = PI / 2;
    const double nominal[27] = {
        50, -55, 35, -35, 35, -35,       /* a1..a6 */
        375, 0, 250, 0, 270, 0,          /* d1..d6 */
        -h, h, -h, h, -h, h,             /* alpha1..alpha6 */
        0, 0, 0, 0, 0, 0,                /* theta1..theta6 */
        0, 0, 100,                       /* Bx, By, Bz */
    };
    AacmmArm *made = NULL;
    ok(aacmm_arm_from_params(6, nominal, 27, &made), "aacmm_arm_from_params");
    ok(aacmm_positions(made, q, POSES * 6, p, POSES * 3), "aacmm_positions (params arm)");
    print_bits("nominal_positions", p, POSES * 3);

    /* Error paths: codes, never crashes. */
    AacmmArm *none = (AacmmArm *)&none; /* must be reset to NULL on error */
    expect(aacmm_positions(NULL, q, 6, p, 3), AACMM_STATUS_NULL_POINTER, "null_arm");
    expect(aacmm_positions(arm, NULL, 6, p, 3), AACMM_STATUS_NULL_POINTER, "null_q");
    expect(aacmm_arm_from_file("no/such/arm.toml", &none), AACMM_STATUS_IO, "missing_file");
    if (none != NULL) {
        fail("a failed aacmm_arm_from_file left *out set");
    }
    expect(aacmm_arm_from_file(poses_path, &none), AACMM_STATUS_INPUT, "not_an_arm_file");
    expect(aacmm_arm_from_file(NULL, &none), AACMM_STATUS_NULL_POINTER, "null_path");
    expect(aacmm_positions(arm, q, 7, p, 3), AACMM_STATUS_LENGTH, "q_len_not_a_multiple");
    expect(aacmm_positions(arm, q, 12, p, 3), AACMM_STATUS_LENGTH, "p_len_short");
    expect(aacmm_jacobians(arm, q, 6, p, 3, jac, 3 * n_params - 1), AACMM_STATUS_LENGTH,
           "jac_len_short");
    expect(aacmm_joint_jacobian(arm, q, joints + 1, jp, 3, jq, 3 * joints), AACMM_STATUS_LENGTH,
           "joint_q_len");
    expect(aacmm_arm_from_params(6, nominal, 26, &none), AACMM_STATUS_LENGTH, "params_len");
    expect(aacmm_arm_from_params(0, nominal, 3, &none), AACMM_STATUS_UNSUPPORTED, "no_joints");
    expect(aacmm_positions(arm, q, 6, q, 3), AACMM_STATUS_INVALID_ARGUMENT, "overlap");
    /* An output inside an input: refused before anything is written. */
    double aliased[27];
    memcpy(aliased, nominal, sizeof aliased);
    expect(aacmm_arm_from_params(6, aliased, 27, (AacmmArm **)&aliased[0]),
           AACMM_STATUS_INVALID_ARGUMENT, "out_in_params");
    if (memcmp(aliased, nominal, sizeof aliased) != 0) {
        fail("an output slot inside params was written");
    }
    expect(aacmm_positions(arm, q, SIZE_MAX - 3, p, (SIZE_MAX - 3) / 2), AACMM_STATUS_LENGTH,
           "huge_q_len");
    expect(aacmm_calibration_params(NULL, params, n_params), AACMM_STATUS_NULL_POINTER,
           "null_calibration");
    expect(aacmm_calibrate_files(arm_path, "no/such/poses.csv", NULL, AACMM_ANGLE_DEG, NULL, NULL),
           AACMM_STATUS_NULL_POINTER, "null_out");
    AacmmCalibration *cal = NULL;
    expect(aacmm_calibrate_files(arm_path, "no/such/poses.csv", NULL, AACMM_ANGLE_DEG, NULL, &cal),
           AACMM_STATUS_IO, "missing_poses");
    /* Options: each setter refuses a value out of range and keeps the one
     * before; names no arm has are refused when set, names this arm lacks
     * when calibrating. */
    AacmmCalibrateOptions *bad = NULL;
    ok(aacmm_calibrate_options_new(&bad), "aacmm_calibrate_options_new");
    expect(aacmm_calibrate_options_set_seed(NULL, 1), AACMM_STATUS_NULL_POINTER, "null_options");
    expect(aacmm_calibrate_options_set_fix(bad, "theta1,theta13"), AACMM_STATUS_INVALID_ARGUMENT,
           "unknown_parameter");
    expect(aacmm_calibrate_options_set_method(bad, 7), AACMM_STATUS_INVALID_ARGUMENT,
           "unknown_method");
    expect(aacmm_calibrate_options_set_robust(bad, 9, 0), AACMM_STATUS_INVALID_ARGUMENT,
           "unknown_robust");
    expect(aacmm_calibrate_options_set_robust(bad, AACMM_ROBUST_HUBER, -1),
           AACMM_STATUS_INVALID_ARGUMENT, "robust_scale");
    expect(aacmm_calibrate_options_set_prior(bad, "length=0.5"), AACMM_STATUS_INVALID_ARGUMENT,
           "prior_without_unit");
    ok(aacmm_calibrate_options_set_fix(bad, "theta7"), "aacmm_calibrate_options_set_fix");
    expect(aacmm_calibrate_files(arm_path, poses_path, NULL, AACMM_ANGLE_DEG, bad, &cal),
           AACMM_STATUS_INVALID_ARGUMENT, "fix_not_in_arm");
    aacmm_calibrate_options_free(bad);
    size_t needed = aacmm_last_error_message(NULL, 0);
    char tiny[8];
    if (aacmm_last_error_message(tiny, sizeof tiny) != needed || strlen(tiny) != sizeof tiny - 1) {
        fail("aacmm_last_error_message did not truncate to the buffer");
    }

    /* Calibration from the files, with the README's flags:
     * --encoder-noise 0.005 (deg) --probe-noise 0.01 --cross-validate 3. */
    AacmmCalibrateOptions *options = NULL;
    ok(aacmm_calibrate_options_new(&options), "aacmm_calibrate_options_new");
    ok(aacmm_calibrate_options_set_encoder_noise_rad(options, 0.005 * (PI / 180.0)),
       "aacmm_calibrate_options_set_encoder_noise_rad");
    ok(aacmm_calibrate_options_set_probe_noise_mm(options, 0.01),
       "aacmm_calibrate_options_set_probe_noise_mm");
    ok(aacmm_calibrate_options_set_cross_validate(options, 3),
       "aacmm_calibrate_options_set_cross_validate");
    ok(aacmm_calibrate_files(arm_path, poses_path, lengths_path, AACMM_ANGLE_DEG, options, &cal),
       "aacmm_calibrate_files");
    double calibrated[31], sigma[31];
    bool fixed[31];
    AacmmCalibrationSummary summary;
    ok(aacmm_calibration_params(cal, calibrated, n_params), "aacmm_calibration_params");
    ok(aacmm_calibration_sigmas(cal, sigma, n_params), "aacmm_calibration_sigmas");
    ok(aacmm_calibration_fixed(cal, fixed, n_params), "aacmm_calibration_fixed");
    ok(aacmm_calibration_summary(cal, &summary), "aacmm_calibration_summary");
    print_bits("files_params", calibrated, n_params);
    print_bits("files_sigmas", sigma, n_params);
    printf("files_fixed");
    for (size_t c = 0; c < n_params; c++) {
        printf(" %d", fixed[c] ? 1 : 0);
    }
    printf("\n");
    printf("files_summary %d %d %d %zu %zu %zu %u\n", (int)summary.termination,
           summary.successful ? 1 : 0, summary.converged ? 1 : 0, summary.iterations,
           summary.free_parameters, summary.degrees_of_freedom, (unsigned)summary.method);

    /* The verdict: usable (the summary's `successful`) and why not, one
     * reason per line; and its notes. */
    bool usable = false;
    size_t reasons_len = 0;
    AacmmStatus sized = aacmm_calibration_verdict(cal, &usable, NULL, 0, &reasons_len);
    char *reasons = malloc(reasons_len + 1);
    ok(aacmm_calibration_verdict(cal, &usable, reasons, reasons_len + 1, &reasons_len),
       "aacmm_calibration_verdict");
    if (sized != AACMM_STATUS_BUFFER_TOO_SMALL || usable != summary.successful) {
        fail("aacmm_calibration_verdict disagrees with the summary or did not size its text");
    }
    print_escaped(usable ? "verdict usable" : "verdict refused", reasons);
    free(reasons);
    char *notes = string_of(aacmm_calibration_verdict_notes, cal, "aacmm_calibration_verdict_notes");
    print_escaped("verdict_notes", notes);
    free(notes);

    size_t report_len = 0;
    expect(aacmm_calibration_report(cal, NULL, 0, &report_len), AACMM_STATUS_BUFFER_TOO_SMALL,
           "report_size");
    char *report = string_of(aacmm_calibration_report, cal, "aacmm_calibration_report");
    print_escaped("report", report);
    free(report);

    /* The uncertainty map: the report's `uncertainty_map`, its summary and
     * each band of distance from the shoulder. */
    AacmmUncertaintyMap map;
    ok(aacmm_calibration_uncertainty_map(cal, &map), "aacmm_calibration_uncertainty_map");
    const double map_values[5] = {map.coverage, map.k_isotropic, map.rms_mm, map.median_mm,
                                  map.max_mm};
    print_bits("map", map_values, 5);
    printf("map_counts %zu %zu\n", map.poses, map.regions);
    size_t region_count = 0;
    ok(aacmm_calibration_uncertainty_region_count(cal, &region_count),
       "aacmm_calibration_uncertainty_region_count");
    if (region_count != map.regions) {
        fail("the region count disagrees with the map's");
    }
    size_t region_poses = 0;
    for (size_t r = 0; r < region_count; r++) {
        AacmmUncertaintyRegion region;
        char tag[32];
        ok(aacmm_calibration_uncertainty_region(cal, r, &region),
           "aacmm_calibration_uncertainty_region");
        snprintf(tag, sizeof tag, "map_region_%zu", r);
        const double values[5] = {region.reach_from_mm, region.reach_to_mm, (double)region.poses,
                                  region.rms_mm, region.max_mm};
        print_bits(tag, values, 5);
        region_poses += region.poses;
    }
    if (region_poses != map.poses) {
        fail("the bands do not hold every pose of the map");
    }
    AacmmUncertaintyRegion region;
    expect(aacmm_calibration_uncertainty_region(cal, region_count, &region),
           AACMM_STATUS_INVALID_ARGUMENT, "map_region_index");
    expect(aacmm_calibration_uncertainty_map(cal, NULL), AACMM_STATUS_NULL_POINTER,
           "map_null_out");
    expect(aacmm_calibration_uncertainty_region(NULL, 0, &region), AACMM_STATUS_NULL_POINTER,
           "map_null_calibration");

    /* The calibrated arm as a handle. */
    AacmmArm *after = NULL;
    ok(aacmm_calibration_arm(cal, &after), "aacmm_calibration_arm");
    ok(aacmm_positions(after, q, POSES * joints, p, POSES * 3), "aacmm_positions (calibrated)");
    print_bits("calibrated_positions", p, POSES * 3);
    aacmm_arm_free(after);

    /* Calibration from arrays: the same campaign, read by this program. */
    static double touches[MAX_TOUCHES * 7];
    static uint32_t points[MAX_TOUCHES];
    static AacmmReferenceLength lengths[MAX_LENGTHS];
    size_t n = read_poses(poses_path, joints, touches, points);
    size_t m = read_lengths(lengths_path, lengths);
    AacmmCalibration *from_arrays = NULL;
    expect(aacmm_calibrate(arm, touches, n * joints, points, n - 1, lengths, m, options,
                           &from_arrays),
           AACMM_STATUS_LENGTH, "points_len");
    ok(aacmm_calibrate(arm, touches, n * joints, points, n, lengths, m, options, &from_arrays),
       "aacmm_calibrate");
    double arrays[31];
    ok(aacmm_calibration_params(from_arrays, arrays, n_params), "aacmm_calibration_params");
    print_bits("arrays_params", arrays, n_params);
    if (memcmp(arrays, calibrated, n_params * sizeof(double)) != 0) {
        fail("arrays and files gave different parameters");
    }

    /* No reference positions, no frame. */
    size_t frame_count = 1;
    ok(aacmm_calibration_frame_count(cal, &frame_count), "aacmm_calibration_frame_count");
    if (frame_count != 0) {
        fail("a calibration on touches has a frame");
    }

    /* Reference positions from arrays: a laser tracker at two stations sees
     * the probe of the nominal arm (`made`) in TRACKED poses each; the
     * calibration on the positions alone finds where the stations stood. */
    static double tq[2 * TRACKED * 6], txyz[2 * TRACKED * 3];
    static uint32_t tframes[2 * TRACKED];
    const char *stations[3] = {"left", "right", "solo"};
    const double turn[2] = {0.5, -1.2}; /* rad about z */
    const double shift[2][3] = {{2500, -400, 300}, {-300, 2800, -150}};
    for (size_t i = 0; i < 2 * TRACKED * 6; i++) {
        tq[i] = 2.5 * sin(0.91 * (double)i + 0.3);
    }
    ok(aacmm_positions(made, tq, 2 * TRACKED * 6, txyz, 2 * TRACKED * 3),
       "aacmm_positions (tracked)");
    for (size_t i = 0; i < 2 * TRACKED; i++) {
        const size_t f = i / TRACKED;
        const double c = cos(turn[f]), s = sin(turn[f]);
        double *y = txyz + 3 * i;
        const double x0 = y[0], x1 = y[1];
        y[0] = c * x0 - s * x1;
        y[1] = s * x0 + c * x1;
        for (size_t k = 0; k < 3; k++) {
            /* The tracker's noise, deterministic: ±0.02 mm. */
            y[k] += shift[f][k] + 0.02 * sin(1.7 * (double)(3 * i + k));
        }
        tframes[i] = (uint32_t)f;
    }
    print_bits("tracker_q", tq, 2 * TRACKED * 6);
    print_bits("tracker_xyz", txyz, 2 * TRACKED * 3);
    AacmmCalibrateOptions *tracking = NULL;
    ok(aacmm_calibrate_options_new(&tracking), "aacmm_calibrate_options_new");
    ok(aacmm_calibrate_options_set_method(tracking, AACMM_METHOD_LM),
       "aacmm_calibrate_options_set_method");
    ok(aacmm_calibrate_options_set_position_noise_mm(tracking, 0.015, 0.006),
       "aacmm_calibrate_options_set_position_noise_mm");
    expect(aacmm_calibrate_options_set_position_noise_mm(tracking, -1, 0),
           AACMM_STATUS_INVALID_ARGUMENT, "position_noise");
    /* Bad arrays, each refused naming the argument: a frame seen once, a
     * position that is not a number, a NULL array. */
    tframes[3] = 2;
    expect(aacmm_calibrate_options_set_positions(tracking, 6, tq, 2 * TRACKED * 6, txyz,
                                                 2 * TRACKED * 3, tframes, 2 * TRACKED,
                                                 stations, 3, NULL, 0),
           AACMM_STATUS_INPUT, "one_row_frame");
    tframes[3] = 0;
    const double seen = txyz[4];
    txyz[4] = NAN;
    expect(aacmm_calibrate_options_set_positions(tracking, 6, tq, 2 * TRACKED * 6, txyz,
                                                 2 * TRACKED * 3, tframes, 2 * TRACKED,
                                                 stations, 2, NULL, 0),
           AACMM_STATUS_INPUT, "nan_xyz");
    txyz[4] = seen;
    expect(aacmm_calibrate_options_set_positions(tracking, 6, tq, 2 * TRACKED * 6, NULL,
                                                 2 * TRACKED * 3, tframes, 2 * TRACKED,
                                                 stations, 2, NULL, 0),
           AACMM_STATUS_NULL_POINTER, "null_xyz");
    /* A positions file is for aacmm_calibrate_files. */
    ok(aacmm_calibrate_options_set_positions_file(tracking, "positions.csv"),
       "aacmm_calibrate_options_set_positions_file");
    AacmmCalibration *tracked = NULL;
    expect(aacmm_calibrate(made, NULL, 0, NULL, 0, NULL, 0, tracking, &tracked),
           AACMM_STATUS_INVALID_ARGUMENT, "positions_file_for_arrays");
    /* The positions alone: no touches. */
    ok(aacmm_calibrate_options_set_positions(tracking, 6, tq, 2 * TRACKED * 6, txyz,
                                             2 * TRACKED * 3, tframes, 2 * TRACKED, stations, 2,
                                             NULL, 0),
       "aacmm_calibrate_options_set_positions");
    ok(aacmm_calibrate(made, NULL, 0, NULL, 0, NULL, 0, tracking, &tracked),
       "aacmm_calibrate (positions)");
    ok(aacmm_calibration_params(tracked, arrays, 27), "aacmm_calibration_params (positions)");
    print_bits("tracker_params", arrays, 27);
    ok(aacmm_calibration_frame_count(tracked, &frame_count), "aacmm_calibration_frame_count");
    printf("tracker_frames %zu\n", frame_count);
    for (size_t f = 0; f < frame_count; f++) {
        AacmmFrame frame;
        char name[32], tag[48];
        size_t name_len = 0;
        ok(aacmm_calibration_frame(tracked, f, &frame, name, sizeof name, &name_len),
           "aacmm_calibration_frame");
        snprintf(tag, sizeof tag, "frame_%s", name);
        double values[21];
        memcpy(values, frame.rotation_deg, sizeof frame.rotation_deg);
        memcpy(values + 3, frame.translation_mm, sizeof frame.translation_mm);
        memcpy(values + 6, frame.small_rotation_sigma_deg,
               sizeof frame.small_rotation_sigma_deg);
        memcpy(values + 9, frame.translation_sigma_mm, sizeof frame.translation_sigma_mm);
        memcpy(values + 12, frame.rotation_matrix, sizeof frame.rotation_matrix);
        print_bits(tag, values, 21);
    }
    AacmmFrame frame;
    char small[3];
    size_t name_len = 0;
    expect(aacmm_calibration_frame(tracked, 0, &frame, small, sizeof small, &name_len),
           AACMM_STATUS_BUFFER_TOO_SMALL, "frame_name_size");
    if (name_len != strlen("left") || strcmp(small, "le") != 0) {
        fail("aacmm_calibration_frame did not size or truncate the name");
    }
    expect(aacmm_calibration_frame(tracked, 2, &frame, NULL, 0, &name_len),
           AACMM_STATUS_INVALID_ARGUMENT, "frame_index");
    /* The same frames as auxiliary columns, the general accessor (which
     * also gives the corrections beyond geometry, when fitted). */
    const size_t aux_count = print_auxiliary(tracked, "tracker_auxiliary", "aux_");
    AacmmAuxiliary column;
    expect(aacmm_calibration_auxiliary(tracked, aux_count, &column, NULL, 0, &name_len),
           AACMM_STATUS_INVALID_ARGUMENT, "auxiliary_index");
    /* Models beyond geometry: a spec is checked when set (the options keep
     * their earlier value); a compliance needs masses, which an arm made
     * from parameters does not state. */
    expect(aacmm_calibrate_options_set_compliance(tracking, "0"),
           AACMM_STATUS_INVALID_ARGUMENT, "compliance_zero");
    expect(aacmm_calibrate_options_set_harmonics(tracking, "2:"),
           AACMM_STATUS_INVALID_ARGUMENT, "harmonics_no_order");
    ok(aacmm_calibrate_options_set_compliance(tracking, "2,3"),
       "aacmm_calibrate_options_set_compliance");
    AacmmCalibration *loaded = NULL;
    expect(aacmm_calibrate(made, NULL, 0, NULL, 0, NULL, 0, tracking, &loaded),
           AACMM_STATUS_INVALID_ARGUMENT, "compliance_without_masses");
    if (loaded != NULL) {
        fail("a refused calibration gave a result");
    }
    aacmm_calibration_free(tracked);
    aacmm_calibrate_options_free(tracking);
    tool_poses(made, tq, txyz, tframes, stations, turn);

    aacmm_calibration_free(from_arrays);
    aacmm_calibration_free(cal);
    aacmm_calibrate_options_free(options);
    aacmm_calibrate_options_free(NULL);
    aacmm_arm_free(made);
    aacmm_arm_free(arm);
    aacmm_arm_free(NULL);
    return failures == 0 ? 0 : 1;
}
