/* gwy_metrics: the 8 areal parameters Sa Sq Sp Sv Sz Ssk Sku Sdr of a Gwyddion Simple Field
 * (.gsf) computed by Gwyddion's libgwyprocess, the peer of `crest metrics FILE --params
 * Sa,Sq,Sp,Sv,Sz,Ssk,Sku,Sdr` (issue 19). Build: `make -C benches/peers` (needs Debian's
 * libgwyddion20-dev and libglib2.0-dev).
 *
 * Usage: gwy_metrics FILE.gsf [threads: 0 = Gwyddion's OpenMP off, 1 = on (default)]
 *
 * Prints the values in crest's units (µm, Sku non-excess = Gwyddion's kurtosis + 3, Sdr in %)
 * and two times on stderr: `read` (fread of the file into the GwyDataField, not part of the
 * comparison) and `compute` (gwy_data_field_get_stats + get_min_max + get_surface_area only,
 * CLOCK_MONOTONIC; the figure issue 19 compares crest's whole process against).
 * Sdr differs by design: Gwyddion triangulates pixel-centred over nx·ny pixels with
 * extrapolated borders, crest (and surfalize) node cells (docs/iso25178.md §2.2). */
#include <libprocess/gwyprocess.h>
#include <libgwyddion/gwyddion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static double unit_to_m(const char *u) {
    if (!u || !*u || !strcmp(u, "m")) return 1.0;
    if (!strcmp(u, "mm")) return 1e-3;
    if (!strcmp(u, "um") || !strcmp(u, "µm")) return 1e-6;
    if (!strcmp(u, "nm")) return 1e-9;
    fprintf(stderr, "unsupported unit %s\n", u);
    exit(2);
}

int main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: %s FILE.gsf [threads 0|1]\n", argv[0]);
        return 2;
    }
    int threads = argc > 2 ? atoi(argv[2]) : 1;
    gwy_threads_set_enabled(threads != 0);
    double t0 = now();
    FILE *f = fopen(argv[1], "rb");
    if (!f) { perror(argv[1]); return 1; }
    char line[512];
    int xres = 0, yres = 0;
    double xreal = 1.0, yreal = 1.0;
    char xyu[64] = "m", zu[64] = "m";
    long hlen = 0;
    /* Header: text lines up to the first NUL, then padding to a multiple of 4. */
    if (!fgets(line, sizeof line, f) || strncmp(line, "Gwyddion Simple Field 1.0", 25)) {
        fprintf(stderr, "%s: not a .gsf\n", argv[1]);
        return 1;
    }
    hlen = strlen(line);
    int c;
    for (;;) {
        c = fgetc(f);
        if (c == EOF) { fprintf(stderr, "truncated header\n"); return 1; }
        if (c == 0) break;
        ungetc(c, f);
        if (!fgets(line, sizeof line, f)) return 1;
        size_t l = strlen(line);
        char *nul = memchr(line, 0, l + 1);
        hlen += l;
        char k[64], v[64];
        if (sscanf(line, " %63[^= ] = %63s", k, v) == 2) {
            if (!strcmp(k, "XRes")) xres = atoi(v);
            else if (!strcmp(k, "YRes")) yres = atoi(v);
            else if (!strcmp(k, "XReal")) xreal = atof(v);
            else if (!strcmp(k, "YReal")) yreal = atof(v);
            else if (!strcmp(k, "XYUnits")) snprintf(xyu, sizeof xyu, "%s", v);
            else if (!strcmp(k, "ZUnits")) snprintf(zu, sizeof zu, "%s", v);
        }
        (void)nul;
    }
    long start = (hlen / 4 + 1) * 4;
    if (xres <= 0 || yres <= 0) { fprintf(stderr, "no XRes/YRes\n"); return 1; }
    fseek(f, start, SEEK_SET);
    size_t n = (size_t)xres * yres;
    float *buf = malloc(n * sizeof *buf);
    if (!buf || fread(buf, sizeof *buf, n, f) != n) { fprintf(stderr, "short data\n"); return 1; }
    fclose(f);
    double xy = unit_to_m(xyu), zs = unit_to_m(zu);
    GwyDataField *field = gwy_data_field_new(xres, yres, xreal * xy, yreal * xy, FALSE);
    gdouble *d = gwy_data_field_get_data(field);
    for (size_t i = 0; i < n; i++) d[i] = zs * buf[i]; /* little-endian host assumed */
    free(buf);
    gwy_data_field_invalidate(field);
    double t1 = now();

    gdouble avg, ra, rms, skew, kurt, min, max, area;
    gwy_data_field_get_stats(field, &avg, &ra, &rms, &skew, &kurt);
    gwy_data_field_get_min_max(field, &min, &max);
    area = gwy_data_field_get_surface_area(field);
    double t2 = now();

    double um = 1e6;
    double proj = gwy_data_field_get_xreal(field) * gwy_data_field_get_yreal(field);
    printf("{\"Sa\":%.17g,\"Sq\":%.17g,\"Sp\":%.17g,\"Sv\":%.17g,\"Sz\":%.17g,"
           "\"Ssk\":%.17g,\"Sku\":%.17g,\"Sdr\":%.17g,\"read_s\":%.6f,\"compute_s\":%.6f,"
           "\"threads\":%d}\n",
           ra * um, rms * um, (max - avg) * um, (avg - min) * um, (max - min) * um, skew,
           kurt + 3.0, (area / proj - 1.0) * 100.0, t1 - t0, t2 - t1, threads);
    fprintf(stderr, "read %.3f s, compute %.3f s\n", t1 - t0, t2 - t1);
    g_object_unref(field);
    return 0;
}
