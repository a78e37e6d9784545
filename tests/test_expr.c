/* Expressions: values against C math (precedence and associativity corners, every function),
 * constant folding, every error with its column, the nesting limit without stack overflow,
 * eval_many against eval for 1 and 2 threads, and two fuzz loops: random trees printed with
 * minimal parentheses against a direct evaluation of the tree, and random or mutated strings
 * that must parse or fail cleanly. */
#include "check.h"
#include "support.h"
#include "pstencil_expr.h"

#include <float.h>
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static const char *const xyz[] = {"x", "y", "z"};

/* Values the compiler cannot fold, so that C math runs in the same library at run time. */
static double V(double a)
{
    volatile double v = a;
    return v;
}


static double sq(double a) { return a * a; }

static int same(double a, double b) { return a == b || (isnan(a) && isnan(b)); }

/* Parse with x, y, z, evaluate at v; NaN (and a failed check) when it does not parse. */
static double ev(const char *text, const double v[3])
{
    char err[256];
    pst_expr *e = pst_expr_parse(text, xyz, 3, err, sizeof err);
    if (!e) {
        fprintf(stderr, "unexpected parse error for \"%s\": %s\n", text, err);
        CHECK(e != NULL);
        return NAN;
    }
    double r = pst_expr_eval(e, v);
    pst_expr_free(e);
    return r;
}

#define VALUE(text, c)                                                                         \
    do {                                                                                       \
        double got_ = ev(text, v), want_ = (c);                                                \
        ++check_count;                                                                         \
        if (!same(got_, want_)) {                                                              \
            ++check_failures;                                                                  \
            fprintf(stderr, "%s:%d: \"%s\" = %.17g, C says %.17g\n", __FILE__, __LINE__, text, \
                    got_, want_);                                                              \
        }                                                                                      \
    } while (0)

static void test_values(void)
{
    const double v[3] = {V(0.3), V(-0.7), V(1.9)};
    const double x = v[0], y = v[1], z = v[2], pi = 3.14159265358979323846;
    /* precedence and associativity */
    VALUE("2^3^2", 512);
    VALUE("-2^2", -4);
    VALUE("(-2)^2", 4);
    VALUE("2*-3", -6);
    VALUE("1-2-3", -4);
    VALUE("8/2/2", 2);
    VALUE("2^-1", 0.5);
    VALUE("2^-2^2", 1.0 / 16);
    VALUE("6/2*3", 9);
    VALUE("1+2*3", 7);
    VALUE("(1+2)*3", 9);
    VALUE("--2", 2);
    VALUE("+-+2", -2);
    VALUE("2*3^2", 18);
    VALUE("-x^-2", -pow(x, -2));
    VALUE("-x^2", -(x * x));
    VALUE("x^2", x * x); /* a square is a product, as C compilers make pow(x, 2) */
    VALUE("x^y", pow(x, y));
    VALUE("pow(y, 2)", y * y);
    VALUE("x - -y", x - -y);
    VALUE("-x*y", -x * y);
    /* numbers and constants */
    VALUE(".5", 0.5);
    VALUE("5.", 5);
    VALUE("1e3", 1000);
    VALUE("1E+2", 100);
    VALUE("2.5e-3", 2.5e-3);
    VALUE("1e-320", 1e-320); /* subnormal: in range */
    VALUE("pi", pi);
    VALUE("e", 2.71828182845904523536);
    VALUE("2e-3*pi*x", 2e-3 * pi * x);
    /* the scene-file examples */
    VALUE("sin(6*x+8*y)", sin(6 * x + 8 * y));
    VALUE("exp(-((9*x-2)^2+(9*y-2)^2)/4)",
          exp(-(sq(9 * x - 2) + sq(9 * y - 2)) / 4));
    VALUE("0.75*exp(-(9*x-2)^2/4 - (9*y-2)^2/4) + 0.5*exp(-((9*x-7)^2+(9*y-3)^2)/4)",
          0.75 * exp(-sq(9 * x - 2) / 4 - sq(9 * y - 2) / 4) +
              0.5 * exp(-(sq(9 * x - 7) + sq(9 * y - 3)) / 4));
    VALUE("x^2 + y^2 + z^2", x * x + y * y + z * z);
    VALUE(" \t x\n*\ry ", x * y);
    /* every function, against the C function of the same variables */
    static const struct {
        const char *text;
        double (*c)(double);
        int var;
    } f1[] = {{"sin(x)", sin, 0},     {"cos(y)", cos, 1},   {"tan(z)", tan, 2},
              {"asin(x)", asin, 0},   {"acos(y)", acos, 1}, {"atan(z)", atan, 2},
              {"sinh(z)", sinh, 2},   {"cosh(y)", cosh, 1}, {"tanh(x)", tanh, 0},
              {"exp(z)", exp, 2},     {"log(z)", log, 2},   {"log10(z)", log10, 2},
              {"sqrt(z)", sqrt, 2},   {"abs(y)", fabs, 1}};
    for (size_t k = 0; k < sizeof f1 / sizeof *f1; ++k)
        VALUE(f1[k].text, f1[k].c(v[f1[k].var]));
    static const struct {
        const char *text;
        double (*c)(double, double);
        int a, b;
    } f2[] = {{"atan2(y, x)", atan2, 1, 0}, {"pow(z, y)", pow, 2, 1}, {"min(x, y)", fmin, 0, 1},
              {"max(x, y)", fmax, 0, 1},    {"hypot(x, y)", hypot, 0, 1}};
    for (size_t k = 0; k < sizeof f2 / sizeof *f2; ++k)
        VALUE(f2[k].text, f2[k].c(v[f2[k].a], v[f2[k].b]));
    VALUE("floor(y)", -1);
    VALUE("ceil(y)", -0.0);
    VALUE("sign(y)", -1);
    VALUE("sign(x)", 1);
    VALUE("sign(0)", 0);
    VALUE("sin (x)", sin(x));
    VALUE("atan2(sin(x)*2, cos(y)^2+1)", atan2(sin(x) * 2, sq(cos(y)) + 1));
    /* constant arguments, folded at compile time by the same code */
    VALUE("sin(1)+2^0.5", sin(V(1)) + pow(V(2), V(0.5)));
    VALUE("exp(1)/3", exp(V(1)) / 3);
    /* non-finite results are values */
    VALUE("log(-1)", NAN);
    VALUE("1/0", INFINITY);
    VALUE("-1/0", -INFINITY);
    VALUE("sqrt(x-1)", NAN);
    VALUE("10^400", INFINITY);
    /* evaluation of a constant needs no values */
    pst_expr *e = pst_expr_parse("3*4", NULL, 0, NULL, 0);
    CHECK(e && pst_expr_eval(e, NULL) == 12);
    pst_expr_free(e);
    CHECK(isnan(pst_expr_eval(NULL, v)));
    pst_expr_free(NULL);
}

static void test_vars(void)
{
    const char *const vars[] = {"x", "y", "z", "t", "u_1", "e", "sin"};
    char err[256];
    pst_expr *e = pst_expr_parse("u_1*t - e + sin(sin)", vars, 7, err, sizeof err);
    CHECK(e != NULL);
    if (!e)
        return;
    double v[7] = {1, 2, 3, 4, 5, 6, 7};
    CHECK(pst_expr_eval(e, v) == 5.0 * 4 - 6 + sin(V(7))); /* 'e' is the variable here */
    CHECK(!pst_expr_uses(e, 0) && !pst_expr_uses(e, 1) && !pst_expr_uses(e, 2));
    CHECK(pst_expr_uses(e, 3) && pst_expr_uses(e, 4) && pst_expr_uses(e, 5) && pst_expr_uses(e, 6));
    CHECK(!pst_expr_uses(e, -1) && !pst_expr_uses(e, 7) && !pst_expr_uses(e, 99));
    CHECK(!pst_expr_is_constant(e));
    /* a used variable without a value reads as NaN: no crash */
    CHECK(isnan(pst_expr_eval(e, NULL)));
    pst_expr_free(e);

    e = pst_expr_parse("pi*2 + 0*x", xyz, 3, err, sizeof err); /* x appears: not constant */
    CHECK(e && pst_expr_uses(e, 0) && !pst_expr_is_constant(e));
    pst_expr_free(e);
    e = pst_expr_parse("pi*2", xyz, 3, err, sizeof err);
    CHECK(e && pst_expr_is_constant(e) && !pst_expr_uses(e, 0));
    pst_expr_free(e);

    /* 16 variables */
    const char *const many[] = {"a", "b", "c", "d", "f", "g", "h", "i",
                                "j", "k", "l", "m", "n", "o", "p", "q"};
    double mv[16];
    for (int i = 0; i < 16; ++i)
        mv[i] = i + 1;
    e = pst_expr_parse("a+b+c+d+f+g+h+i+j+k+l+m+n+o+p+q", many, 16, err, sizeof err);
    CHECK(e && pst_expr_eval(e, mv) == 136);
    CHECK(e && pst_expr_uses(e, 15));
    pst_expr_free(e);
}

static void test_folding(void)
{
    const double v[3] = {V(0.3), V(-0.7), V(1.9)};
    const double x = v[0];
    struct {
        const char *text;
        size_t length;
        double want;
    } cases[] = {
        {"2*pi+sin(1)", 1, 2 * 3.14159265358979323846 + sin(V(1))},
        {"-(2^0.5)", 1, -pow(V(2), V(0.5))},
        {"atan2(1, 2) * hypot(3, 4)", 1, atan2(V(1), V(2)) * 5},
        {"x + (sin(1)+2)", 3, x + (sin(V(1)) + 2)},
        {"(1+2)*x^(3-1)", 5, 3 * pow(x, 2)},
        {"x*2*3", 5, x * 2 * 3}, /* no reassociation: (x*2)*3 */
        {"2*3*x", 3, 6 * x},
        {"max(1, 2) + x", 3, 2 + x},
        {"-x", 2, -x},
        {"-2", 1, -2},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; ++i) {
        pst_expr *e = pst_expr_parse(cases[i].text, xyz, 3, NULL, 0);
        CHECK(e != NULL);
        if (!e)
            continue;
        CHECK_INT(pst_expr_length(e), cases[i].length);
        CHECK(pst_expr_eval(e, v) == cases[i].want);
        pst_expr_free(e);
    }
}

static void check_error(const char *text, const char *want, int line)
{
    char err[256] = "untouched";
    pst_expr *e = pst_expr_parse(text, xyz, 3, err, sizeof err);
    ++check_count;
    if (e || strcmp(err, want)) {
        ++check_failures;
        fprintf(stderr, "%s:%d: \"%.60s\": got %s \"%s\", want \"%s\"\n", __FILE__, line, text,
                e ? "success" : "error", e ? "" : err, want);
    }
    pst_expr_free(e);
}
#define ERROR(text, want) check_error(text, want, __LINE__)

static void test_errors(void)
{
    ERROR("", "column 1: empty expression");
    ERROR("  \t", "column 1: empty expression");
    ERROR("1+", "column 3: expected a number, name or '(', found end of input");
    ERROR("(", "column 2: expected a number, name or '(', found end of input");
    ERROR(")", "column 1: expected a number, name or '(', found ')'");
    ERROR("()", "column 2: expected a number, name or '(', found ')'");
    ERROR("2*x + sinn(y)", "column 7: unknown function 'sinn'");
    ERROR("x(2)", "column 1: unknown function 'x'");
    ERROR("(1 2", "column 4: expected ')'");
    ERROR("((x)", "column 5: expected ')'");
    ERROR("sin(6*x", "column 8: expected ')'");
    ERROR("atan2(1 2)", "column 9: expected ','");
    ERROR("q", "column 1: unknown variable 'q' (known: x, y, z)");
    ERROR("x + yy", "column 5: unknown variable 'yy' (known: x, y, z)");
    ERROR("atan2(1)", "column 1: function 'atan2' takes 2 arguments");
    ERROR("1 + pow(1, 2, 3)", "column 5: function 'pow' takes 2 arguments");
    ERROR("sin(1, 2)", "column 1: function 'sin' takes 1 argument");
    ERROR("sin()", "column 1: function 'sin' takes 1 argument");
    ERROR("sin x", "column 1: function 'sin' needs its arguments in parentheses: sin(...)");
    ERROR("1)", "column 2: expected an operator or the end, found ')'");
    ERROR("1 2", "column 3: expected an operator or the end, found '2'");
    ERROR("2x", "column 2: expected an operator or the end, found 'x'");
    ERROR("1.2.3", "column 4: expected an operator or the end, found '.3'");
    ERROR("x,y", "column 2: expected an operator or the end, found ','");
    ERROR("0x10", "column 2: expected an operator or the end, found 'x10'");
    ERROR("1e999", "column 1: number '1e999' is out of range");
    ERROR("x*1.8e308", "column 3: number '1.8e308' is out of range");
    ERROR("1e", "column 1: malformed number '1e' (exponent without digits)");
    ERROR("2*3e+", "column 3: malformed number '3e+' (exponent without digits)");
    ERROR("x # y", "column 3: unexpected character '#'");
    ERROR("x\x80", "column 2: unexpected byte 0x80");
    ERROR("1 ** 2", "column 4: expected a number, name or '(', found '*'");
    ERROR("x^", "column 3: expected a number, name or '(', found end of input");
    ERROR(".", "column 1: unexpected character '.'");
    ERROR("inf", "column 1: unknown variable 'inf' (known: x, y, z)");

    char err[256];
    CHECK(!pst_expr_parse("q", NULL, 0, err, sizeof err) &&
          !strcmp(err, "column 1: unknown variable 'q' (known: none)"));
    CHECK(!pst_expr_parse(NULL, xyz, 3, err, sizeof err) && !strcmp(err, "no expression"));
    const char *const dup[] = {"x", "y", "x"};
    CHECK(!pst_expr_parse("x", dup, 3, err, sizeof err) &&
          !strcmp(err, "variable 'x' given twice"));
    const char *const bad[] = {"x", "2y"};
    CHECK(!pst_expr_parse("x", bad, 2, err, sizeof err) &&
          !strcmp(err, "variable 2: '2y' is not a name"));
    const char *const null_name[] = {"x", NULL};
    CHECK(!pst_expr_parse("x", null_name, 2, err, sizeof err) &&
          !strcmp(err, "variable 2: '' is not a name"));
    CHECK(!pst_expr_parse("x", xyz, 17, err, sizeof err) && !strncmp(err, "bad number", 10));
    CHECK(!pst_expr_parse("x", xyz, -1, err, sizeof err) && !strncmp(err, "bad number", 10));
    CHECK(!pst_expr_parse("x", NULL, 1, err, sizeof err) && !strncmp(err, "bad number", 10));
    /* small or absent buffers: truncated, terminated, never overrun */
    char tiny[8];
    memset(tiny, 'z', sizeof tiny);
    CHECK(!pst_expr_parse("sinn(1)", xyz, 3, tiny, 5) && !strcmp(tiny, "colu") && tiny[5] == 'z');
    CHECK(!pst_expr_parse("sinn(1)", xyz, 3, tiny, 0) && tiny[0] == 'c');
    CHECK(!pst_expr_parse("sinn(1)", xyz, 3, NULL, 100));
    /* a long name is cut in the message */
    char longname[200];
    memset(longname, 'a', sizeof longname - 1);
    longname[sizeof longname - 1] = '\0';
    CHECK(!pst_expr_parse(longname, xyz, 3, err, sizeof err) && strlen(err) < 120);
}

/* Text of `reps` copies of open, then mid, then `reps` copies of close. */
static char *nest(const char *open, const char *mid, const char *close, size_t reps)
{
    size_t lo = strlen(open), lm = strlen(mid), lc = strlen(close);
    char *s = malloc(reps * (lo + lc) + lm + 1), *p = s;
    for (size_t i = 0; i < reps; ++i, p += lo)
        memcpy(p, open, lo);
    memcpy(p, mid, lm);
    p += lm;
    for (size_t i = 0; i < reps; ++i, p += lc)
        memcpy(p, close, lc);
    *p = '\0';
    return s;
}

static void check_nest(const char *open, const char *mid, const char *close, size_t reps,
                       const char *want_err, int line)
{
    char err[256] = "";
    char *s = nest(open, mid, close, reps);
    pst_expr *e = pst_expr_parse(s, xyz, 3, err, sizeof err);
    ++check_count;
    if (want_err ? e || strcmp(err, want_err) : !e) {
        ++check_failures;
        fprintf(stderr, "%s:%d: %zu x \"%s\": got \"%s\"\n", __FILE__, line, reps, open, err);
    }
    if (e && !want_err) {
        const double v[3] = {0.5, 0.25, 2};
        double r = pst_expr_eval(e, v);
        CHECK(isfinite(r));
    }
    pst_expr_free(e);
    free(s);
}
#define NEST(o, m, c, reps, want) check_nest(o, m, c, reps, want, __LINE__)

static void test_limits(void)
{
    const char *deep = "column 257: expression nested too deeply (limit 256 levels)";
    NEST("(", "x", ")", 256, NULL);
    NEST("(", "x", ")", 257, deep);
    NEST("(", "x", ")", 100000, deep);
    NEST("(", "", "", 100000, deep);
    NEST("-", "x", "", 256, NULL);
    NEST("-", "x", "", 100000, deep);
    NEST("sin(", "x", ")", 256, NULL);
    NEST("sin(", "x", ")", 100000, "column 1025: expression nested too deeply (limit 256 levels)");
    NEST("x^", "x", "", 256, NULL);
    NEST("x^", "x", "", 100000, "column 514: expression nested too deeply (limit 256 levels)");

    /* The deepest evaluation stack the limit allows: four values wait per level pair. */
    char *s = nest("atan2(y, y + y*y^", "x", ")", 128);
    char err[256];
    pst_expr *e = pst_expr_parse(s, xyz, 3, err, sizeof err);
    CHECK(e != NULL);
    if (e) {
        const double v[3] = {V(0.5), V(0.75), V(2)};
        double want = v[0];
        for (int i = 0; i < 128; ++i)
            want = atan2(v[1], v[1] + v[1] * pow(v[1], want));
        CHECK(pst_expr_eval(e, v) == want);
        double col[3][300], out[300];
        for (int k = 0; k < 300; ++k)
            for (int d = 0; d < 3; ++d)
                col[d][k] = v[d];
        const double *cols[3] = {col[0], col[1], col[2]};
        pst_expr_eval_many(e, 300, cols, out);
        int bad = 0;
        for (int k = 0; k < 300; ++k)
            bad += out[k] != want;
        CHECK_INT(bad, 0);
    }
    pst_expr_free(e);
    free(s);
    s = nest("atan2(y, y + y*y^", "x", ")", 129);
    CHECK(!pst_expr_parse(s, xyz, 3, NULL, 0));
    free(s);

    /* Left-associative chains are loops, not recursion: any length. */
    size_t terms = 100000;
    s = malloc(2 * terms);
    for (size_t i = 0; i < terms; ++i) {
        s[2 * i] = 'x';
        s[2 * i + 1] = i + 1 < terms ? '+' : '\0';
    }
    e = pst_expr_parse(s, xyz, 3, err, sizeof err);
    const double one[3] = {1, 0, 0};
    CHECK(e && pst_expr_eval(e, one) == (double)terms);
    pst_expr_free(e);
    free(s);
}

static void test_many(void)
{
    const char *texts[] = {
        "sin(6*x+8*y)",
        "0.75*exp(-(9*x-2)^2/4 - (9*y-2)^2/4) + 0.5*exp(-((9*x-7)^2+(9*y-3)^2)/4)",
        "x^2 + y^2 + z^2",
        "log(x) + sqrt(y)", /* NaN for negative inputs */
        "2*pi",
        "-x^-2",
    };
    enum { N = 10007 };
    double *col[3], *out = malloc(N * sizeof *out);
    for (int d = 0; d < 3; ++d) {
        col[d] = malloc(N * sizeof *col[d]);
        for (int k = 0; k < N; ++k)
            col[d][k] = 2 * test_rnd() - 0.5;
    }
    for (size_t t = 0; t < sizeof texts / sizeof *texts; ++t) {
        pst_expr *e = pst_expr_parse(texts[t], xyz, 3, NULL, 0);
        CHECK(e != NULL);
        if (!e)
            continue;
        /* unused columns may be NULL; a constant needs no columns at all */
        const double *cols[3] = {pst_expr_uses(e, 0) ? col[0] : NULL,
                                 pst_expr_uses(e, 1) ? col[1] : NULL,
                                 pst_expr_uses(e, 2) ? col[2] : NULL};
        for (int threads = 1; threads <= 2; ++threads) {
            omp_set_num_threads(threads);
            for (size_t n = 0; n <= N; n += N / 3 + (n == 0)) {
                memset(out, 0, N * sizeof *out);
                pst_expr_eval_many(e, n, pst_expr_is_constant(e) ? NULL : cols, out);
                int bad = 0;
                for (size_t k = 0; k < n; ++k) {
                    double v[3] = {col[0][k], col[1][k], col[2][k]};
                    double r = pst_expr_eval(e, v);
                    bad += memcmp(&r, &out[k], sizeof r) != 0;
                }
                CHECK_INT(bad, 0);
            }
        }
        pst_expr_free(e);
    }
    pst_expr *e = NULL;
    pst_expr_eval_many(e, 3, NULL, out);
    CHECK(isnan(out[0]) && isnan(out[2]));
    for (int d = 0; d < 3; ++d)
        free(col[d]);
    free(out);
}

/* ---- fuzz (i): random trees ---------------------------------------------------------- */

enum { N_NUM, N_VAR, N_NEG, N_ADD, N_SUB, N_MUL, N_DIV, N_POW, N_F1, N_F2 };

typedef struct node {
    int kind, which; /* N_NUM: literal index; N_VAR: variable; N_F1/N_F2: function index */
    struct node *a, *b;
} node;

static const struct {
    const char *text;
    double value;
} literals[] = {{"0", 0},       {"1", 1},       {"2", 2},         {"3", 3},       {"0.5", 0.5},
                {".25", .25},   {"1e-3", 1e-3}, {"2.5E2", 2.5E2}, {"7.", 7.},     {"1e+1", 1e+1},
                {"pi", 3.14159265358979323846}, {"e", 2.71828182845904523536}};

static const char *const f1_names[] = {"sin",  "cos",  "tan",   "asin", "acos",  "atan",
                                       "sinh", "cosh", "tanh",  "exp",  "log",   "log10",
                                       "sqrt", "abs",  "floor", "ceil", "sign"};
static double (*const f1[])(double) = {sin,  cos, tan,  asin, acos,  atan,  sinh, cosh, tanh,
                                       exp,  log, log10, sqrt, fabs, floor, ceil, NULL};
static const char *const f2_names[] = {"atan2", "pow", "min", "max", "hypot"};
static double power(double a, double b) { return b == 2 ? a * a : pow(a, b); }
static double (*const f2[])(double, double) = {atan2, power, fmin, fmax, hypot};

static node pool[4096];
static int pool_used;

static node *gen(int depth)
{
    node *n = &pool[pool_used++];
    *n = (node){0, 0, NULL, NULL};
    int leaf = depth <= 0 || test_rndi(4) == 0 || pool_used > 4000;
    if (leaf) {
        n->kind = test_rndi(2) ? N_VAR : N_NUM;
        n->which = n->kind == N_VAR ? test_rndi(3)
                                    : test_rndi((int)(sizeof literals / sizeof *literals));
        return n;
    }
    n->kind = N_NEG + test_rndi(N_F2 - N_NEG + 1);
    if (n->kind == N_F1)
        n->which = test_rndi((int)(sizeof f1 / sizeof *f1));
    if (n->kind == N_F2)
        n->which = test_rndi((int)(sizeof f2 / sizeof *f2));
    n->a = gen(depth - 1);
    if (n->kind != N_NEG && n->kind != N_F1)
        n->b = gen(depth - 1);
    return n;
}

static double sgn(double a) { return a > 0 ? 1.0 : a < 0 ? -1.0 : a; }

static double ref(const node *n, const double *v)
{
    switch (n->kind) {
    case N_NUM: return literals[n->which].value;
    case N_VAR: return v[n->which];
    case N_NEG: return -ref(n->a, v);
    case N_ADD: return ref(n->a, v) + ref(n->b, v);
    case N_SUB: return ref(n->a, v) - ref(n->b, v);
    case N_MUL: return ref(n->a, v) * ref(n->b, v);
    case N_DIV: return ref(n->a, v) / ref(n->b, v);
    case N_POW: { /* an exponent of exactly 2 squares (docs/expressions.md) */
        double a = ref(n->a, v), b = ref(n->b, v);
        return b == 2 ? a * a : pow(a, b);
    }
    case N_F1: return f1[n->which] ? f1[n->which](ref(n->a, v)) : sgn(ref(n->a, v));
    default: return f2[n->which](ref(n->a, v), ref(n->b, v));
    }
}

/* Binding strength as printed: sums 1, products 2, signs 3, powers 4, atoms 5. */
static int prec(const node *n)
{
    static const int p[] = {5, 5, 3, 1, 1, 2, 2, 4, 5, 5};
    return p[n->kind];
}

typedef struct {
    char s[16384];
    size_t len;
} buf;

static void put(buf *b, const char *t)
{
    if (test_rndi(5) == 0)
        b->s[b->len++] = ' ';
    size_t l = strlen(t);
    memcpy(b->s + b->len, t, l);
    b->len += l;
}

static void print(buf *b, const node *n, int need_parens);

static void child(buf *b, const node *c, int min_prec)
{
    print(b, c, prec(c) < min_prec);
}

/* Print with the fewest parentheses the grammar needs, plus some redundant ones. */
static void print(buf *b, const node *n, int need_parens)
{
    int parens = need_parens || test_rndi(12) == 0;
    static const char *const ops[] = {"", "", "-", "+", "-", "*", "/", "^"};
    if (parens)
        put(b, "(");
    switch (n->kind) {
    case N_NUM: put(b, literals[n->which].text); break;
    case N_VAR: put(b, xyz[n->which]); break;
    case N_NEG:
        put(b, "-");
        child(b, n->a, 3);
        break;
    case N_ADD: case N_SUB: case N_MUL: case N_DIV: {
        int p = prec(n);
        child(b, n->a, p);     /* left-associative: an equal left operand needs none */
        put(b, ops[n->kind]);
        child(b, n->b, p + 1); /* an equal right one does */
        break;
    }
    case N_POW:
        child(b, n->a, 5); /* a base binds tighter than a sign or power: (-x)^2, (x^y)^z */
        put(b, "^");
        child(b, n->b, 3); /* an exponent may carry a sign or be a power: x^-y^z */
        break;
    case N_F1:
        put(b, f1_names[n->which]);
        put(b, "(");
        child(b, n->a, 0);
        put(b, ")");
        break;
    default:
        put(b, f2_names[n->which]);
        put(b, "(");
        child(b, n->a, 0);
        put(b, ",");
        child(b, n->b, 0);
        put(b, ")");
        break;
    }
    if (parens)
        put(b, ")");
    b->s[b->len] = '\0';
}

static int close_enough(double a, double b)
{
    if (isnan(a) || isnan(b))
        return isnan(a) && isnan(b);
    if (isinf(a) || isinf(b))
        return a == b;
    return fabs(a - b) <= 1e-12 * fmax(fabs(a), fabs(b));
}

static buf text;

static void test_fuzz_trees(void)
{
    test_rng_seed(2024);
    int bad = 0, failed_parse = 0, exact = 0, total = 0;
    for (int t = 0; t < 6000; ++t) {
        pool_used = 0;
        node *root = gen(1 + test_rndi(7));
        text.len = 0;
        print(&text, root, 0);
        char err[256];
        pst_expr *e = pst_expr_parse(text.s, xyz, 3, err, sizeof err);
        if (!e) {
            if (++failed_parse <= 5)
                fprintf(stderr, "fuzz: \"%s\": %s\n", text.s, err);
            continue;
        }
        for (int p = 0; p < 3; ++p) {
            double v[3] = {4 * test_rnd() - 2, 4 * test_rnd() - 2, 4 * test_rnd() - 2};
            double want = ref(root, v), got = pst_expr_eval(e, v);
            ++total;
            exact += same(want, got);
            if (!close_enough(got, want) && ++bad <= 5)
                fprintf(stderr, "fuzz: \"%s\" at (%g, %g, %g) = %.17g, tree says %.17g\n",
                        text.s, v[0], v[1], v[2], got, want);
        }
        pst_expr_free(e);
    }
    CHECK_INT(failed_parse, 0);
    CHECK_INT(bad, 0);
    /* The same operations in the same order: bit for bit, in fact. */
    CHECK_INT(exact, total);
}

/* ---- fuzz (ii): random and mutated strings ------------------------------------------- */

/* Parse `s`: either an expression that evaluates (to anything) or a "column N: " message with
 * N within the text; returns 1 when it parsed. */
static int parse_or_fail_cleanly(const char *s, int *bad)
{
    char err[256];
    memset(err, 0, sizeof err);
    pst_expr *e = pst_expr_parse(s, xyz, 3, err, sizeof err);
    if (e) {
        const double v[3] = {0.5, -1.5, 2.5};
        volatile double r = pst_expr_eval(e, v);
        (void)r;
        pst_expr_free(e);
        return 1;
    }
    unsigned long col = 0;
    if (sscanf(err, "column %lu: ", &col) != 1 || col < 1 || col > strlen(s) + 1 ||
        strlen(err) >= sizeof err - 1) {
        if (++*bad <= 5)
            fprintf(stderr, "fuzz: \"%s\": bad message \"%s\"\n", s, err);
    }
    return 0;
}

static void test_fuzz_strings(void)
{
    test_rng_seed(77);
    static const char alphabet[] = "0123456789.eE+-*/^(),xyzpi sincoqrtlgabmhfdp_ \t#";
    int bad = 0, parsed = 0;
    char s[128];
    for (int t = 0; t < 20000; ++t) {
        int len = test_rndi(40);
        for (int i = 0; i < len; ++i)
            s[i] = test_rndi(16) ? alphabet[test_rndi((int)sizeof alphabet - 1)]
                                 : (char)(1 + test_rndi(255));
        s[len] = '\0';
        parsed += parse_or_fail_cleanly(s, &bad);
    }
    for (int t = 0; t < 6000; ++t) {
        pool_used = 0;
        text.len = 0;
        print(&text, gen(1 + test_rndi(5)), 0);
        for (int m = 1 + test_rndi(3); m > 0; --m) {
            size_t len = text.len, at = len ? (size_t)test_rndi((int)len) : 0;
            switch (test_rndi(5)) {
            case 0: /* delete */
                if (len)
                    memmove(text.s + at, text.s + at + 1, len - at);
                text.len -= len > 0;
                break;
            case 1: /* insert */
                memmove(text.s + at + 1, text.s + at, len - at + 1);
                text.s[at] = alphabet[test_rndi((int)sizeof alphabet - 1)];
                ++text.len;
                break;
            case 2: /* replace with any byte */
                if (len)
                    text.s[at] = (char)(1 + test_rndi(255));
                break;
            case 3: /* truncate */
                text.len = at;
                text.s[at] = '\0';
                break;
            default: /* duplicate a piece */
                if (len && len < 8000) {
                    size_t l = (size_t)test_rndi((int)(len - at)) + 1;
                    memmove(text.s + at + l, text.s + at, len - at + 1);
                    text.len += l;
                }
                break;
            }
        }
        parsed += parse_or_fail_cleanly(text.s, &bad);
    }
    CHECK_INT(bad, 0);
    CHECK(parsed > 100); /* the mutations leave some valid expressions */
}

int main(void)
{
    double t0 = omp_get_wtime();
    test_values();
    test_vars();
    test_folding();
    test_errors();
    test_limits();
    test_many();
    test_fuzz_trees();
    test_fuzz_strings();
    printf("test_expr: %.2f s\n", omp_get_wtime() - t0);
    return check_summary("test_expr");
}
