/* Progress hooks: the counter and the try-lock that keep the hook's calls serial and its counts
 * non-decreasing (tally.h). */
#include "tally.h"

pst_tally *pst_tally_start(pst_tally *t, const pst_progress *p, uint64_t total)
{
    if (!p || !p->fn)
        return NULL;
    t->hook = *p;
    t->total = total;
    atomic_init(&t->done, 0);
    atomic_flag_clear(&t->busy);
    t->shown = 0;
    return t;
}

/* The count read after taking the lock is at least what any earlier holder read, since the
 * counter only grows: so the hook's counts never go back. */
void pst_tally_report(pst_tally *t, uint64_t units)
{
    atomic_fetch_add_explicit(&t->done, units, memory_order_relaxed);
    if (atomic_flag_test_and_set_explicit(&t->busy, memory_order_acquire))
        return; /* someone is reporting; the count is kept for the next report */
    uint64_t done = atomic_load_explicit(&t->done, memory_order_relaxed);
    if (done > t->total)
        done = t->total;
    if (done > t->shown) {
        t->shown = done;
        t->hook.fn(t->hook.user, done, t->total);
    }
    atomic_flag_clear_explicit(&t->busy, memory_order_release);
}

void pst_tally_finish(pst_tally *t)
{
    if (!t)
        return;
    t->shown = t->total;
    t->hook.fn(t->hook.user, t->total, t->total);
}
