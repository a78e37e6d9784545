/* The full reproduction of Lukyanov–Vuik Tables 2-9 (LV §5.1, §5.2;
 * docs/lv-tables.md): §5.1 all-Dirichlet and §5.2 mixed problems on the cell-centred layout,
 * DoF 5^2 .. 160^2, uniform and perturbed (30 realisations, mean ± standard deviation), for
 * cb, schwaiger and lv, with a TPFA column (the paper's MPFA = TPFA on uniform grids); error
 * (95), successive rates, markdown tables. The problem builders and the TPFA reference are
 * tests/lv_problems.c and tests/tpfa_ref.c.
 *
 * usage: lv_tables [--max-side N] [--reals R] [--tables 2,3,...]
 *   --max-side  finest side (default 160)      --reals  realisations of the random tables (30)
 */
#include "lv_problems.h"
#include "pstencil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    int number;
    lv_problem prob;
    double f;
    int perturbed;
} table;

static const table tables[] = {
    {2, LV_DIRICHLET_ALL, 0.5005, 0}, {3, LV_DIRICHLET_ALL, 1.001, 0},
    {4, LV_DIRICHLET_ALL, 0.6006, 1}, {5, LV_DIRICHLET_ALL, 1.2012, 1},
    {6, LV_MIXED, 0.5005, 0},         {7, LV_MIXED, 1.001, 0},
    {8, LV_MIXED, 0.6006, 1},         {9, LV_MIXED, 1.2012, 1},
};
static const char *const schemes[3] = {"cb", "schwaiger", "lv"};

int main(int argc, char **argv)
{
    int max_side = 160, reals = 30, want[10] = {0, 0, 1, 1, 1, 1, 1, 1, 1, 1};
    for (int a = 1; a < argc; ++a) {
        if (!strcmp(argv[a], "--max-side") && a + 1 < argc)
            max_side = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--reals") && a + 1 < argc)
            reals = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--tables") && a + 1 < argc) {
            memset(want, 0, sizeof want);
            for (char *t = strtok(argv[++a], ","); t; t = strtok(NULL, ","))
                if (atoi(t) >= 2 && atoi(t) <= 9)
                    want[atoi(t)] = 1;
        } else {
            fprintf(stderr, "usage: lv_tables [--max-side N] [--reals R] [--tables 2,3,..]\n");
            return 2;
        }
    }
    char err[PST_ERRLEN];
    for (size_t t = 0; t < sizeof tables / sizeof *tables; ++t) {
        const table *tb = &tables[t];
        if (!want[tb->number])
            continue;
        int R = tb->perturbed ? reals : 1;
        printf("\n### Table %d: %s, f = %.4f%s\n\n", tb->number,
               tb->prob == LV_DIRICHLET_ALL ? "§5.1 Dirichlet" : "§5.2 mixed", tb->f,
               tb->perturbed ? ", perturbed (mean ± std)" : ", uniform");
        printf("| DoF | TPFA | CB (51) | Schwaiger | New (lv) | failed solves |\n|---|---|---|---|---|---|\n");
        double prev[4] = {0}, cur[4];
        char rates[16][128];
        int nrates = 0;
        for (int n = 5; n <= max_side; n *= 2) {
            double m[3] = {0}, m2[3] = {0};
            int failed = 0;
            for (int r = 0; r < R; ++r) {
                lv_case pc;
                if (lv_case_build(&pc, tb->prob, n, tb->f, tb->perturbed ? LV_JITTER : 0,
                                  1000 + (uint64_t)r, err) != PST_OK) {
                    fprintf(stderr, "lv_tables: %s\n", err);
                    return 1;
                }
                double *u = malloc(pc.n * sizeof *u);
                for (int s = 0; s < 3; ++s) {
                    if (lv_solve_scheme(&pc, schemes[s], u, NULL, err) != PST_OK) {
                        ++failed;
                        fprintf(stderr, "table %d %s %d^2 #%d: %s\n", tb->number, schemes[s], n, r, err);
                    }
                    double e = lv_error95(pc.cloud, pc.exact, u);
                    m[s] += e / R;
                    m2[s] += e * e / R;
                }
                free(u);
                lv_case_free(&pc);
            }
            double tp = 0;
            if (lv_tpfa_error(tb->prob, n, &tp, err) != 0)
                fprintf(stderr, "lv_tables: tpfa: %s\n", err);
            printf("| %d | %.3e |", n * n, tp);
            cur[0] = tp;
            for (int s = 0; s < 3; ++s) {
                cur[s + 1] = m[s];
                if (tb->perturbed)
                    printf(" %.3e ± %.2e |", m[s], sqrt(fmax(0, m2[s] - m[s] * m[s])));
                else
                    printf(" %.3e |", m[s]);
            }
            printf(" %d |\n", failed);
            fflush(stdout);
            if (prev[0] > 0 && nrates < 16) {
                snprintf(rates[nrates++], sizeof rates[0], "%d→%d: %.2f %.2f %.2f %.2f", n * n / 4,
                         n * n, log2(prev[0] / cur[0]), log2(prev[1] / cur[1]),
                         log2(prev[2] / cur[2]), log2(prev[3] / cur[3]));
            }
            memcpy(prev, cur, sizeof prev);
        }
        printf("\nRates (TPFA, CB, Schwaiger, New):");
        for (int k = 0; k < nrates; ++k)
            printf("%s %s", k ? ";" : "", rates[k]);
        printf("\n");
    }
    return 0;
}
