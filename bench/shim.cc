// Google Benchmark behind the C interface of bench_shim.h, and the benchmark program's main.
#include "bench_shim.h"

#include <benchmark/benchmark.h>

struct pstb_state {
    benchmark::State *st;
};

extern "C" void pstb_register_iters(const char *name, pstb_fn fn, const int64_t *args,
                                    int nargs, int64_t iterations)
{
    auto *b = benchmark::RegisterBenchmark(name, [fn](benchmark::State &st) {
        pstb_state s{&st};
        fn(&s);
    });
    for (int i = 0; i < nargs; ++i)
        b->Arg(args[i]);
    b->UseRealTime()->Unit(benchmark::kMillisecond);
    if (iterations > 0)
        b->Iterations(iterations);
}

extern "C" void pstb_register(const char *name, pstb_fn fn, const int64_t *args, int nargs)
{
    pstb_register_iters(name, fn, args, nargs, 0);
}

extern "C" int pstb_keep_running(pstb_state *s) { return s->st->KeepRunning(); }
extern "C" int64_t pstb_arg(const pstb_state *s) { return s->st->range(0); }
extern "C" void pstb_pause(pstb_state *s) { s->st->PauseTiming(); }
extern "C" void pstb_resume(pstb_state *s) { s->st->ResumeTiming(); }
extern "C" void pstb_skip(pstb_state *s, const char *message) { s->st->SkipWithError(message); }

extern "C" void pstb_counter(pstb_state *s, const char *name, double value, int rate)
{
    s->st->counters[name] = benchmark::Counter(
        value, rate ? benchmark::Counter::kIsIterationInvariantRate : benchmark::Counter::kDefaults);
}

extern "C" void pstb_context(const char *key, const char *value)
{
    benchmark::AddCustomContext(key, value);
}

int main(int argc, char **argv)
{
    pstb_register_all();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv))
        return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
