/*
 * LS-C: the least-squares sphere fit of Gamage & Lasenby (2002) (paper A's LS, cost f2) in C99,
 * the worked example of an estimator in a compiled language (README, "Adding an estimator").
 *
 *   ls_sphere DATASET.csv > ESTIMATES.csv
 *
 * Reads a condition's markers as plain CSV (jointbench.resultfiles.interchange: a header naming
 * trial, segment, frame, marker, x, y, z, one row per sample, trial by trial), fits every trial
 * of the "moving" segment and writes one CSV row per trial:
 *
 *   trial,center_x,center_y,center_z,converged,iterations,seconds,status
 *
 * For each marker p over the N frames of a trial, with v the position relative to the trial's
 * first sample (far from the origin |v|^2 would lose the radii to rounding):
 *   A = 2/N sum_p sum_k (v - mean v)(v - mean v)^T
 *   b = 1/N sum_p sum_k (v - mean v)(|v|^2 - mean |v|^2)
 * and the centre solves A c = b (Cholesky). A matrix that is not clearly positive definite (a
 * hinge, markers that do not move) makes the trial a failed row: this program has no
 * pseudo-inverse, and says so rather than guess.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { TRIAL, SEGMENT, FRAME, MARKER, X, Y, Z, N_COLUMNS };
static const char *COLUMN_NAMES[N_COLUMNS] = {"trial", "segment", "frame", "marker",
                                              "x",     "y",       "z"};

typedef struct {
    long trial;
    long marker;
    double p[3];
} Sample;

static void die(const char *what, const char *detail) {
    fprintf(stderr, "ls_sphere: %s%s\n", what, detail ? detail : "");
    exit(1);
}

/* The position of each needed column in the header line, or exit naming the one missing. */
static void read_header(char *line, int position[N_COLUMNS]) {
    for (int c = 0; c < N_COLUMNS; c++) position[c] = -1;
    int index = 0;
    for (char *field = strtok(line, ",\r\n"); field; field = strtok(NULL, ",\r\n"), index++) {
        for (int c = 0; c < N_COLUMNS; c++)
            if (strcmp(field, COLUMN_NAMES[c]) == 0) position[c] = index;
    }
    for (int c = 0; c < N_COLUMNS; c++)
        if (position[c] < 0) die("missing column ", COLUMN_NAMES[c]);
}

/* Parse one data line into a sample; returns 0 for a sample of another segment. */
static int read_sample(char *line, const int position[N_COLUMNS], long row, Sample *sample) {
    char *fields[64];
    int n = 0;
    for (char *field = strtok(line, ",\r\n"); field && n < 64; field = strtok(NULL, ",\r\n"))
        fields[n++] = field;
    for (int c = 0; c < N_COLUMNS; c++) {
        if (position[c] >= n) {
            char where[64];
            snprintf(where, sizeof where, "%ld", row);
            die("too few fields in data row ", where);
        }
    }
    if (strcmp(fields[position[SEGMENT]], "moving") != 0) return 0;
    sample->trial = strtol(fields[position[TRIAL]], NULL, 10);
    sample->marker = strtol(fields[position[MARKER]], NULL, 10);
    sample->p[0] = strtod(fields[position[X]], NULL);
    sample->p[1] = strtod(fields[position[Y]], NULL);
    sample->p[2] = strtod(fields[position[Z]], NULL);
    return 1;
}

/* Solve the symmetric 3 x 3 system a c = b by Cholesky; 0 when a is not clearly positive
 * definite (its smallest pivot below 1e-10 of its trace, the scale of the rank threshold). */
static int cholesky_solve(double a[3][3], const double b[3], double c[3]) {
    double l[3][3] = {{0}};
    double trace = a[0][0] + a[1][1] + a[2][2];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j <= i; j++) {
            double sum = a[i][j];
            for (int k = 0; k < j; k++) sum -= l[i][k] * l[j][k];
            if (i == j) {
                if (!(sum > 1e-10 * trace)) return 0;
                l[i][i] = sqrt(sum);
            } else {
                l[i][j] = sum / l[j][j];
            }
        }
    }
    double y[3];
    for (int i = 0; i < 3; i++) {
        double sum = b[i];
        for (int k = 0; k < i; k++) sum -= l[i][k] * y[k];
        y[i] = sum / l[i][i];
    }
    for (int i = 2; i >= 0; i--) {
        double sum = y[i];
        for (int k = i + 1; k < 3; k++) sum -= l[k][i] * c[k];
        c[i] = sum / l[i][i];
    }
    return 1;
}

/* Fit the samples of one trial and print its row. */
static void fit_trial(const Sample *samples, long count) {
    clock_t start = clock();
    long n_markers = 0;
    for (long i = 0; i < count; i++)
        if (samples[i].marker + 1 > n_markers) n_markers = samples[i].marker + 1;
    double *mean = calloc((size_t)n_markers * 4, sizeof *mean);
    long *frames = calloc((size_t)n_markers, sizeof *frames);
    if (!mean || !frames) die("out of memory", NULL);
    const double *origin = samples[0].p;
    for (long i = 0; i < count; i++) {
        double *m = mean + 4 * samples[i].marker;
        double v[3], sq = 0.0;
        for (int d = 0; d < 3; d++) {
            v[d] = samples[i].p[d] - origin[d];
            sq += v[d] * v[d];
            m[d] += v[d];
        }
        m[3] += sq;
        frames[samples[i].marker]++;
    }
    for (long p = 0; p < n_markers; p++)
        for (int d = 0; d < 4; d++) mean[4 * p + d] /= (double)(frames[p] ? frames[p] : 1);
    double a[3][3] = {{0}}, b[3] = {0};
    for (long i = 0; i < count; i++) {
        const double *m = mean + 4 * samples[i].marker;
        double v[3], sq = 0.0, x[4];
        for (int d = 0; d < 3; d++) {
            v[d] = samples[i].p[d] - origin[d];
            sq += v[d] * v[d];
        }
        for (int d = 0; d < 3; d++) x[d] = v[d] - m[d];
        x[3] = sq - m[3];
        for (int r = 0; r < 3; r++) {
            for (int c = 0; c < 3; c++) a[r][c] += x[r] * x[c];
            b[r] += x[r] * x[3];
        }
    }
    long n_frames = frames[0];
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) a[r][c] *= 2.0 / (double)n_frames;
        b[r] /= (double)n_frames;
    }
    double center[3];
    int solved = cholesky_solve(a, b, center);
    double seconds = (double)(clock() - start) / CLOCKS_PER_SEC;
    if (solved) {
        printf("%ld,%.17g,%.17g,%.17g,true,0,%.9g,ok\n", samples[0].trial,
               origin[0] + center[0], origin[1] + center[1], origin[2] + center[2], seconds);
    } else {
        printf("%ld,nan,nan,nan,false,0,%.9g,error: A is not positive definite "
               "(markers on a hinge or not moving)\n",
               samples[0].trial, seconds);
    }
    free(mean);
    free(frames);
}

int main(int argc, char **argv) {
    if (argc != 2) die("usage: ls_sphere DATASET.csv > ESTIMATES.csv", NULL);
    FILE *in = fopen(argv[1], "r");
    if (!in) die("cannot open ", argv[1]);
    char line[4096];
    if (!fgets(line, sizeof line, in)) die("empty file ", argv[1]);
    int position[N_COLUMNS];
    read_header(line, position);

    long capacity = 1 << 16, count = 0, row = 0;
    Sample *samples = malloc((size_t)capacity * sizeof *samples);
    if (!samples) die("out of memory", NULL);
    printf("trial,center_x,center_y,center_z,converged,iterations,seconds,status\n");
    long first = 0;
    while (fgets(line, sizeof line, in)) {
        Sample sample;
        if (!read_sample(line, position, ++row, &sample)) continue;
        if (count > first && sample.trial != samples[first].trial) {
            fit_trial(samples + first, count - first);
            first = count;
        }
        if (count == capacity) {
            capacity *= 2;
            samples = realloc(samples, (size_t)capacity * sizeof *samples);
            if (!samples) die("out of memory", NULL);
        }
        samples[count++] = sample;
    }
    if (count > first) fit_trial(samples + first, count - first);
    free(samples);
    fclose(in);
    return 0;
}
