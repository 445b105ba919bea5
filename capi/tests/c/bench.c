/*
 * Batch positions through the C API, timed: the C half of the C-vs-Rust
 * comparison that the example positions_timing runs
 * (cargo run --release -p aacmm-capi --example positions_timing):
 *
 *   bench N REPS   → "c_positions N MEDIAN_NS MIN_NS CPU_NS CHECKSUM"
 *
 * N poses of the paper's nominal arm, q[i] = 3 sin(0.37 i + 0.1) rad; each
 * of REPS calls of aacmm_positions is timed (after one warm-up call): the
 * median and the fastest wall-clock call, and the processor time per call
 * (clock(): user + system, what a loaded machine disturbs least), in ns,
 * with a sum of positions so that the work cannot be optimised away.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "aacmm.h"

#define PI 3.14159265358979323846

static double now_ns(void) {
    struct timespec ts;
    timespec_get(&ts, TIME_UTC);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

static int by_value(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: %s N REPS\n", argv[0]);
        return 2;
    }
    size_t n = (size_t)strtoull(argv[1], NULL, 10);
    int reps = atoi(argv[2]);
    double *q = malloc(n * 6 * sizeof *q), *p = malloc(n * 3 * sizeof *p);
    double *times = malloc((size_t)reps * sizeof *times);
    if (q == NULL || p == NULL || times == NULL || reps < 1) {
        return 2;
    }
    for (size_t i = 0; i < n * 6; i++) {
        q[i] = 3.0 * sin(0.37 * (double)i + 0.1);
    }
    const double h = PI / 2;
    const double nominal[27] = {
        50, -55, 35, -35, 35, -35, 375, 0, 250, 0, 270, 0, -h, h, -h, h, -h, h,
        0,  0,   0,  0,   0,  0,   0,   0, 100,
    };
    AacmmArm *arm = NULL;
    if (aacmm_arm_from_params(6, nominal, 27, &arm) != AACMM_STATUS_OK ||
        aacmm_positions(arm, q, n * 6, p, n * 3) != AACMM_STATUS_OK) {
        fprintf(stderr, "bench: the C API failed\n");
        return 1;
    }
    double checksum = 0;
    clock_t cpu0 = clock();
    for (int r = 0; r < reps; r++) {
        double t0 = now_ns();
        aacmm_positions(arm, q, n * 6, p, n * 3);
        times[r] = now_ns() - t0;
        checksum += p[0] + p[n * 3 - 1];
    }
    double cpu = (double)(clock() - cpu0) / CLOCKS_PER_SEC * 1e9 / reps;
    qsort(times, (size_t)reps, sizeof *times, by_value);
    printf("c_positions %zu %.0f %.0f %.0f %.17g\n", n, times[reps / 2], times[0], cpu, checksum);
    aacmm_arm_free(arm);
    free(q);
    free(p);
    free(times);
    return 0;
}
