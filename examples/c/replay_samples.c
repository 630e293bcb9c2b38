/*
 * Replays conditioned samples through the aeroident C library and prints the estimates as
 * `aeroident replay` writes estimates.csv: `t_s,<names>,sigma_<names>`, one row per accepted
 * sample, an empty cell where a parameter is not identified (or has no sigma).
 *
 *   replay_samples KIND MODEL_FILE SAMPLES_CSV [OPTIONS] > estimates.csv
 *
 * KIND is an estimator (rls, ftr, ekf ...), MODEL_FILE a model file (its text is passed to the
 * library) or a preset name, OPTIONS the estimator's options as TOML (`forgetting = 0.99`).
 * SAMPLES_CSV holds the samples the estimator consumes, one per row, columns named as the
 * fields of AeroidentSample (an empty cell: absent) plus `manoeuvre` (a new number starts a new
 * manoeuvre, as a gap does in a replay). `cargo run --release -p aeroident-capi --example
 * conditioned_samples` writes such a file from a flight record: the samples `aeroident replay`
 * feeds its estimator (docs/c-abi.md).
 *
 * Build (after `cargo build --release -p aeroident-capi`):
 *   gcc -std=c11 -O2 -Wall -Wextra -Icrates/capi/include examples/c/replay_samples.c \
 *       target/release/libaeroident_capi.a -lpthread -ldl -lm -o replay_samples
 */
#include "aeroident.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Where each CSV column goes in an AeroidentSample, and its presence bit (0: always read). */
struct column {
    const char *name;
    size_t offset;
    uint32_t bit;
};

#define COL(field, bit) {#field, offsetof(AeroidentSample, field), bit}
static const struct column COLUMNS[] = {
    COL(t_s, 0), COL(vt_mps, 0), COL(alpha_rad, 0), COL(qbar_pa, 0),
    COL(beta_rad, AEROIDENT_HAS_BETA), COL(p_rad_s, AEROIDENT_HAS_P),
    COL(q_rad_s, AEROIDENT_HAS_Q), COL(r_rad_s, AEROIDENT_HAS_R),
    COL(pdot_rad_s2, AEROIDENT_HAS_PDOT), COL(qdot_rad_s2, AEROIDENT_HAS_QDOT),
    COL(rdot_rad_s2, AEROIDENT_HAS_RDOT), COL(alphadot_rad_s, AEROIDENT_HAS_ALPHADOT),
    COL(phi_rad, AEROIDENT_HAS_PHI), COL(theta_rad, AEROIDENT_HAS_THETA),
    COL(psi_rad, AEROIDENT_HAS_PSI), COL(ax_mps2, AEROIDENT_HAS_AX),
    COL(ay_mps2, AEROIDENT_HAS_AY), COL(az_mps2, AEROIDENT_HAS_AZ),
    COL(de_rad, AEROIDENT_HAS_DE), COL(da_rad, AEROIDENT_HAS_DA),
    COL(dr_rad, AEROIDENT_HAS_DR), COL(thrust_n, AEROIDENT_HAS_THRUST),
    COL(throttle, AEROIDENT_HAS_THROTTLE), COL(thrust_moment_nm, AEROIDENT_HAS_THRUST_MOMENT),
    COL(rho_kgpm3, AEROIDENT_HAS_RHO), COL(mass_kg, 0), COL(S_m2, 0),
    COL(cbar_m, AEROIDENT_HAS_CBAR), COL(b_m, AEROIDENT_HAS_B),
    COL(Ixx_kgm2, AEROIDENT_HAS_IXX), COL(Iyy_kgm2, AEROIDENT_HAS_IYY),
    COL(Izz_kgm2, AEROIDENT_HAS_IZZ), COL(Ixz_kgm2, AEROIDENT_HAS_IXZ),
    COL(thrust_arm_m, 0), COL(thrust_incidence_rad, 0), COL(v0_mps, AEROIDENT_HAS_V0),
};
#define N_COLUMNS (sizeof COLUMNS / sizeof COLUMNS[0])
#define MAX_CELLS 64
#define LINE_MAX_BYTES 8192

/* The whole file `path`, NUL-terminated (malloc'ed), or the preset name itself. */
static char *model_text(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        char *copy = malloc(strlen(path) + 1);
        return copy ? strcpy(copy, path) : NULL; /* a preset name: the library says if not */
    }
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *text = malloc((size_t)n + 1);
    if (text && fread(text, 1, (size_t)n, f) != (size_t)n) {
        free(text);
        text = NULL;
    }
    fclose(f);
    if (text) text[n] = '\0';
    return text;
}

/* Splits `line` at commas in place (the trailing newline removed); returns the cell count. */
static int split(char *line, char **cells) {
    line[strcspn(line, "\r\n")] = '\0';
    int n = 0;
    for (char *p = line;; ++p) {
        if (n == MAX_CELLS) return -1;
        cells[n++] = p;
        p = strchr(p, ',');
        if (!p) return n;
        *p = '\0';
    }
}

/* For each column of the header, its index in COLUMNS (-1: `manoeuvre`, -2: unknown). */
static int map_header(char **cells, int n, int *slot, int *manoeuvre) {
    *manoeuvre = -1;
    for (int k = 0; k < n; ++k) {
        slot[k] = -2;
        if (strcmp(cells[k], "manoeuvre") == 0) {
            *manoeuvre = k;
            slot[k] = -1;
        }
        for (size_t c = 0; c < N_COLUMNS; ++c)
            if (strcmp(cells[k], COLUMNS[c].name) == 0) slot[k] = (int)c;
        if (slot[k] == -2) {
            fprintf(stderr, "samples: unknown column `%s`\n", cells[k]);
            return -1;
        }
    }
    return 0;
}

/* One row into `s`; returns 0, or -1 naming the bad cell on stderr. */
static int parse_row(char **cells, int n, const int *slot, long row, AeroidentSample *s) {
    memset(s, 0, sizeof *s);
    for (int k = 0; k < n; ++k) {
        if (slot[k] < 0 || cells[k][0] == '\0') continue; /* manoeuvre, or absent */
        char *end;
        double v = strtod(cells[k], &end);
        if (*end != '\0') {
            fprintf(stderr, "samples: row %ld: `%s` is not a number\n", row, cells[k]);
            return -1;
        }
        const struct column *c = &COLUMNS[slot[k]];
        memcpy((char *)s + c->offset, &v, sizeof v);
        s->present |= c->bit;
    }
    return 0;
}

static void print_header(const AeroidentEstimator *e, size_t n) {
    printf("t_s");
    for (size_t i = 0; i < n; ++i) printf(",%s", aeroident_estimator_param_name(e, i));
    for (size_t i = 0; i < n; ++i) printf(",sigma_%s", aeroident_estimator_param_name(e, i));
    printf("\n");
}

static void print_cell(double v) {
    if (isnan(v)) printf(",");
    else printf(",%.17g", v);
}

/* One estimates row (the numbers in full: %.17g reads back to the same double). */
static int print_row(const AeroidentEstimator *e, double t_s, size_t n) {
    double value[128], sigma[128];
    if (aeroident_estimator_estimates(e, value, sigma, NULL, sizeof value / sizeof value[0]) !=
        AEROIDENT_RESULT_OK) {
        fprintf(stderr, "estimates: %s\n", aeroident_last_error_message());
        return -1;
    }
    printf("%.17g", t_s);
    for (size_t i = 0; i < n; ++i) print_cell(value[i]);
    for (size_t i = 0; i < n; ++i) print_cell(sigma[i]);
    printf("\n");
    return 0;
}

/* Feeds every row of `f` to `e`, printing the estimates after each accepted sample. */
static int replay(AeroidentEstimator *e, FILE *f) {
    static char line[LINE_MAX_BYTES];
    char *cells[MAX_CELLS];
    int slot[MAX_CELLS], manoeuvre_column;
    if (!fgets(line, sizeof line, f)) return fprintf(stderr, "samples: empty\n"), -1;
    int n_cells = split(line, cells);
    if (n_cells < 0 || map_header(cells, n_cells, slot, &manoeuvre_column) != 0) return -1;
    size_t n = aeroident_estimator_n_params(e);
    print_header(e, n);
    long row = 1, manoeuvre = 0;
    while (fgets(line, sizeof line, f)) {
        ++row;
        AeroidentSample s;
        if (split(line, cells) != n_cells || parse_row(cells, n_cells, slot, row, &s) != 0) {
            fprintf(stderr, "samples: row %ld is not a sample\n", row);
            return -1;
        }
        long m = manoeuvre_column >= 0 ? strtol(cells[manoeuvre_column], NULL, 10) : 0;
        if (m != manoeuvre) {
            aeroident_estimator_new_manoeuvre(e);
            manoeuvre = m;
        }
        AeroidentResult r = aeroident_estimator_update(e, &s);
        if (r == AEROIDENT_RESULT_SAMPLE_REFUSED) {
            fprintf(stderr, "row %ld: %s\n", row, aeroident_last_error_message());
            continue;
        }
        if (r != AEROIDENT_RESULT_OK) {
            fprintf(stderr, "row %ld: %s\n", row, aeroident_last_error_message());
            return r == AEROIDENT_RESULT_DIVERGED ? 0 : -1;
        }
        if (print_row(e, s.t_s, n) != 0) return -1;
    }
    return 0;
}

/* The final verdicts, one line per parameter on stderr: `verdict NAME STATUS`, then the
 * parameter's flags, each on a line of its own indented by two spaces. */
static void print_verdicts(AeroidentEstimator *e) {
    static const char *const names[] = {"identified", "flagged", "not identified", "diverged"};
    AeroidentVerdict verdicts[256];
    size_t n = aeroident_estimator_n_params(e);
    if (aeroident_estimator_verdicts(e, verdicts, sizeof verdicts / sizeof verdicts[0]) !=
        AEROIDENT_RESULT_OK) {
        fprintf(stderr, "verdicts: %s\n", aeroident_last_error_message());
        return;
    }
    for (size_t i = 0; i < n; ++i) {
        fprintf(stderr, "verdict %s %s\n", aeroident_estimator_param_name(e, i),
                names[verdicts[i]]);
        const char *flags = aeroident_estimator_flags(e, i);
        for (const char *p = flags; p && *p;) {
            const char *end = strchr(p, '\n');
            int len = end ? (int)(end - p) : (int)strlen(p);
            fprintf(stderr, "  %.*s\n", len, p);
            p = end ? end + 1 : p + len;
        }
    }
}

int main(int argc, char **argv) {
    if (argc < 4 || argc > 5) {
        fprintf(stderr, "usage: %s KIND MODEL_FILE SAMPLES_CSV [OPTIONS]\n", argv[0]);
        return 2;
    }
    char *model = model_text(argv[2]);
    FILE *samples = fopen(argv[3], "r");
    if (!model || !samples) {
        fprintf(stderr, "cannot read %s\n", model ? argv[3] : argv[2]);
        return 1;
    }
    AeroidentEstimator *e = NULL;
    if (aeroident_estimator_new(argv[1], model, argc == 5 ? argv[4] : NULL, &e) !=
        AEROIDENT_RESULT_OK) {
        fprintf(stderr, "%s\n", aeroident_last_error_message());
        return 1;
    }
    int failed = replay(e, samples);
    print_verdicts(e);
    AeroidentState state;
    if (aeroident_estimator_state(e, &state) == AEROIDENT_RESULT_OK)
        fprintf(stderr, "%s: %llu samples accepted, %llu refused, %zu of %zu identified\n",
                aeroident_estimator_method(e), (unsigned long long)state.samples_accepted,
                (unsigned long long)state.samples_refused, state.n_identified, state.n_params);
    aeroident_estimator_free(e);
    fclose(samples);
    free(model);
    return failed ? 1 : 0;
}
