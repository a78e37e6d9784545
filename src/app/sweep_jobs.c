/* Several sweep runs at once (docs/sweeps.md, "Runs at once"). Small runs go to worker
 * processes, each a `pstencil sweep FILE --worker DIGEST` with a share of the threads that
 * runs the combinations it is sent; large runs wait until the workers are idle and run here,
 * alone, with every thread. Workers are separate programs, not forks: a fork after libgomp's
 * threads or MPI have started is not safe, and a fresh program has neither.
 *
 * The protocol, one stream socket per worker (its fd 3): the parent sends "K\n", the worker
 * answers one line of compact JSON (sweep_worker.c). A worker that dies fails the run it had;
 * the others go on, and with none left the rest run here. */
#define _POSIX_C_SOURCE 200809L /* posix_spawn, socketpair, MSG_NOSIGNAL, F_DUPFD_CLOEXEC */

#include "sweep_jobs.h"

#include "plan.h"
#include "progress.h"
#include "sweep_grid.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

/* A run is small when its plan has at most this many neighbour pairs (about a tenth of a
 * second of one thread's precompute in 3D) and `jobs` copies of its memory estimate fit. */
#define SMALL_PAIRS 4e6
/* A cloud read from a file counts as small when the file has at most this many bytes (its
 * particle count is known only once it is read). */
#define SMALL_FILE_BYTES (1 << 20)
/* The most workers a sweep starts. */
#define MAX_JOBS 256

int sweep_combo_is_small(const pst_sweep *sw, size_t k, int jobs)
{
    pst_scene s;
    char msg[PST_ERRLEN * 2];
    if (sweep_combo_scene(sw, k, &s, msg, sizeof msg) != PST_OK)
        return 0;
    int small = 0;
    size_t n = pst_plan_particles(&s);
    pst_plan p;
    if (n == 0 && s.cloud.file) {
        struct stat sb;
        small = stat(s.cloud.file, &sb) == 0 && sb.st_size <= SMALL_FILE_BYTES;
    } else if (pst_plan_make(&p, &s, n, NULL, msg, sizeof msg) == PST_OK) {
        small = (double)p.particles * (p.neighbours + 1) <= SMALL_PAIRS &&
                jobs * p.bytes_total <= s.memory_fraction * p.bytes_available;
    }
    pst_scene_free(&s);
    return small;
}

typedef struct {
    pid_t pid;    /* 0: not running (never started, or ended)                               */
    int fd;       /* the parent's end of the socket                                          */
    long k;       /* the combination it runs, -1 when idle                                   */
    char *buf;    /* the answer so far                                                        */
    size_t len, cap;
} worker;

/* The parent's socket end moved above the standard descriptors, close-on-exec (the worker's
 * end becomes its fd 3 by dup2, which clears the flag there). */
static int high_cloexec(int fd)
{
    int h = fcntl(fd, F_DUPFD_CLOEXEC, 10);
    close(fd);
    return h;
}

static int start_worker(worker *w, const char *exe, const char *path, int threads,
                        const char *digest)
{
    int sv[2];
    memset(w, 0, sizeof *w);
    w->k = -1;
    w->fd = -1;
    if (socketpair(AF_UNIX, SOCK_STREAM, 0, sv) != 0)
        return -1;
    sv[0] = high_cloexec(sv[0]);
    sv[1] = high_cloexec(sv[1]);
    char nthreads[16];
    snprintf(nthreads, sizeof nthreads, "%d", threads);
    char *argv[] = {(char *)exe, "--threads", nthreads, "--quiet", "sweep", (char *)path,
                    "--worker", (char *)digest, NULL};
    posix_spawn_file_actions_t fa;
    int ok = sv[0] >= 0 && sv[1] >= 0 && posix_spawn_file_actions_init(&fa) == 0;
    if (ok) {
        ok = posix_spawn_file_actions_adddup2(&fa, sv[1], 3) == 0 &&
             posix_spawn(&w->pid, exe, &fa, NULL, argv, environ) == 0;
        posix_spawn_file_actions_destroy(&fa);
    }
    if (sv[1] >= 0)
        close(sv[1]);
    if (!ok) {
        if (sv[0] >= 0)
            close(sv[0]);
        w->pid = 0;
        return -1;
    }
    w->fd = sv[0];
    return 0;
}

/* Close the worker's socket (it exits at the end of its input) and wait for it; the reason
 * it ended, for a message, in why. */
static void stop_worker(worker *w, char *why, size_t len)
{
    if (w->fd >= 0)
        close(w->fd);
    int wst = 0;
    if (w->pid > 0 && waitpid(w->pid, &wst, 0) == w->pid && why) {
        if (WIFSIGNALED(wst))
            snprintf(why, len, "ended by signal %d (%s)", WTERMSIG(wst), strsignal(WTERMSIG(wst)));
        else
            snprintf(why, len, "ended with exit status %d", WEXITSTATUS(wst));
    } else if (why) {
        snprintf(why, len, "ended");
    }
    free(w->buf);
    memset(w, 0, sizeof *w);
    w->fd = -1;
    w->k = -1;
}

static int send_combo(worker *w, size_t k)
{
    char line[32];
    int n = snprintf(line, sizeof line, "%zu\n", k);
    if (send(w->fd, line, (size_t)n, MSG_NOSIGNAL) != n)
        return -1;
    w->k = (long)k;
    w->len = 0;
    return 0;
}

/* The sweep's state while runs are out. */
typedef struct {
    const pst_sweep *sw;
    const pst_sweep_opts *o;
    sweep_rows *j;
    pst_sweep_stats *stats;
    cli_progress pg;
    size_t todo, made;
    int busy;
    char label[512];   /* the run started last                                              */
    char detail[200];  /* the progress line's detail                                        */
} jobs_state;

/* A run has ended (its rows added): rewrite the CSV and the progress line. */
static int run_ended(jobs_state *s, char *err, size_t errlen)
{
    s->made++;
    snprintf(s->detail, sizeof s->detail, "%zu/%zu done, %d running: %.100s", s->made,
             s->todo, s->busy, s->label);
    progress_update(&s->pg, (double)s->made / (double)s->todo, s->detail);
    return sweep_write_rows(s->sw, s->j, err, errlen);
}

/* The rows of worker w's answer line (its buffer up to the newline). */
static int take_answer(jobs_state *s, worker *w)
{
    w->buf[w->len] = '\0';
    cJSON *a = cJSON_Parse(w->buf);
    const cJSON *k = cJSON_GetObjectItemCaseSensitive(a, "k");
    const cJSON *rep = cJSON_GetObjectItemCaseSensitive(a, "report");
    const char *msg = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(a, "message"));
    int ran = cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(a, "ran"));
    int status = (int)cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(a, "status"));
    int st;
    if (!cJSON_IsNumber(k) || k->valuedouble != (double)w->k || !msg) {
        st = sweep_record(s->j, (size_t)w->k, 1, NULL, PST_EIO, "the sweep worker's answer "
                          "is not one this sweep can read", s->stats);
    } else {
        sweep_report_decode((cJSON *)rep);
        s->stats->in_workers += ran;
        st = sweep_record(s->j, (size_t)w->k, ran, cJSON_IsObject(rep) ? rep : NULL, status,
                          msg, s->stats);
    }
    cJSON_Delete(a);
    w->k = -1;
    s->busy--;
    return st;
}

/* Read what worker w has sent; its run's rows once its line is complete. A worker that ends
 * before its answer fails the run (and stops). PST_OK or PST_ENOMEM. */
static int read_worker(jobs_state *s, worker *w, int *ended)
{
    *ended = 0;
    if (w->cap - w->len < 4096) {
        size_t cap = w->cap ? 2 * w->cap : 65536;
        char *b = realloc(w->buf, cap);
        if (!b)
            return PST_ENOMEM;
        w->buf = b;
        w->cap = cap;
    }
    ssize_t n = recv(w->fd, w->buf + w->len, w->cap - w->len - 1, 0);
    if (n < 0 && errno == EINTR)
        return PST_OK;
    if (n <= 0) {
        char why[128], msg[256];
        size_t k = (size_t)w->k;
        stop_worker(w, why, sizeof why);
        snprintf(msg, sizeof msg, "the sweep worker running this combination %s", why);
        s->busy--;
        *ended = 1;
        return sweep_record(s->j, k, 1, NULL, PST_EIO, msg, s->stats);
    }
    char *nl = memchr(w->buf + w->len, '\n', (size_t)n);
    w->len += (size_t)n;
    if (!nl)
        return PST_OK;
    w->len = (size_t)(nl - w->buf);
    *ended = 1;
    return take_answer(s, w);
}

/* Wait for the busy workers and take every answer that came; *ended counts the runs that
 * ended. */
static int collect(jobs_state *s, worker *ws, int nw, int *ended)
{
    struct pollfd pf[MAX_JOBS];
    int map[MAX_JOBS], np = 0;
    *ended = 0;
    for (int q = 0; q < nw; ++q)
        if (ws[q].k >= 0) {
            pf[np] = (struct pollfd){.fd = ws[q].fd, .events = POLLIN};
            map[np++] = q;
        }
    int r = poll(pf, (nfds_t)np, 500);
    if (r <= 0) {
        progress_update(&s->pg, (double)s->made / (double)s->todo, s->detail);
        return PST_OK; /* the clock moves on; EINTR retried by the caller's loop */
    }
    int st = PST_OK;
    for (int p = 0; st == PST_OK && p < np; ++p) {
        if (!(pf[p].revents & (POLLIN | POLLHUP | POLLERR)))
            continue;
        int done;
        st = read_worker(s, &ws[map[p]], &done);
        *ended += done;
    }
    return st;
}

static int idle_worker(const worker *ws, int nw)
{
    for (int q = 0; q < nw; ++q)
        if (ws[q].pid > 0 && ws[q].k < 0)
            return q;
    return -1;
}

/* The runs in order: small ones to idle workers, a large one (or any, with no worker left)
 * here once every worker is idle. */
static int dispatch(jobs_state *s, worker *ws, int nw, const size_t *order, const char *small,
                    char *err, size_t errlen)
{
    size_t next = 0;
    int st = PST_OK;
    while (st == PST_OK && (next < s->todo || s->busy > 0)) {
        int q;
        while (next < s->todo && small[next] && (q = idle_worker(ws, nw)) >= 0) {
            if (send_combo(&ws[q], order[next]) != 0) {
                stop_worker(&ws[q], NULL, 0); /* it ended: the run goes to another */
                continue;
            }
            sweep_combo_label(s->sw, order[next], s->label, sizeof s->label);
            s->busy++;
            next++;
        }
        if (s->busy == 0 && next < s->todo) { /* large, or no worker left */
            sweep_combo_label(s->sw, order[next], s->label, sizeof s->label);
            snprintf(s->detail, sizeof s->detail, "%zu/%zu done, alone: %.100s", s->made,
                     s->todo, s->label);
            progress_update(&s->pg, (double)s->made / (double)s->todo, s->detail);
            st = sweep_run_combo(s->sw, s->o, s->j, order[next++], s->stats);
            if (st == PST_OK)
                st = run_ended(s, err, errlen);
            continue;
        }
        int ended = 0;
        if (s->busy > 0)
            st = collect(s, ws, nw, &ended);
        for (int e = 0; st == PST_OK && e < ended; ++e)
            st = run_ended(s, err, errlen);
    }
    if (st == PST_ENOMEM && !err[0])
        snprintf(err, errlen, "out of memory for the rows");
    return st;
}

int sweep_run_jobs(const pst_sweep *sw, const pst_sweep_opts *o, sweep_rows *j,
                   const char *done, pst_sweep_stats *stats, char *err, size_t errlen)
{
    jobs_state s = {.sw = sw, .o = o, .j = j, .stats = stats};
    size_t *order = malloc((sw->ncombos + 1) * sizeof *order);
    char *small = malloc(sw->ncombos + 1);
    if (!order || !small) {
        free(order);
        free(small);
        snprintf(err, errlen, "out of memory");
        return PST_ENOMEM;
    }
    int jobs = o->jobs < MAX_JOBS ? o->jobs : MAX_JOBS;
    size_t nsmall = 0;
    for (size_t k = 0; k < sw->ncombos; ++k) {
        if (done[k]) {
            stats->skipped++;
            continue;
        }
        order[s.todo] = k;
        small[s.todo] = (char)sweep_combo_is_small(sw, k, jobs);
        nsmall += (size_t)small[s.todo++];
    }
    if ((size_t)jobs > nsmall)
        jobs = (int)nsmall;
    int threads = pst_threads() / (jobs > 0 ? jobs : 1);
    char digest[32];
    snprintf(digest, sizeof digest, "%016llx", (unsigned long long)sweep_digest(sw));
    worker ws[MAX_JOBS];
    int nw = 0;
    for (; nw < jobs; ++nw)
        if (start_worker(&ws[nw], o->worker_exe, sw->path, threads > 0 ? threads : 1,
                         digest) != 0)
            break; /* fewer workers; with none every run goes here */
    progress_begin(&s.pg, !o->quiet, "sweep", NULL);
    int st = dispatch(&s, ws, nw, order, small, err, errlen);
    for (int q = 0; q < nw; ++q)
        if (ws[q].pid > 0)
            stop_worker(&ws[q], NULL, 0);
    progress_update(&s.pg, 1, "");
    progress_end(&s.pg);
    free(order);
    free(small);
    return st;
}
