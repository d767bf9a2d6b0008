/* The planar matcher over a sweep of m in one call (module ``_matching_kernels``, see module.c).
 *
 * What ursim_core/matching/single.py's match_at does at each m, for the C loop's case: the seeds
 * of SeedSelector.at(m) (the ``cap`` lowest pairs of c, ties by position, in position order), the
 * relation ``c <= m``, the pair costs of the hypothesis score, and planar_run. The automatic m
 * matches a turned KTH sketch at about 600 values of m; a call per m spent more in Python around
 * the loop than in it. A building-sized pair's values of m (0.13 s each at 8000 px) are shared
 * between threads, each with its own scratch: 2.6 s on one thread, 1.5 s on two (19 values).
 */
#include "kernels.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

static int by_position(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

/* What every worker of a sweep reads, and where it leaves each m's outcome. */
typedef struct {
    const Planar *model; /* the graphs and options; each worker has its own scratch */
    const double *c, *values, *ms;
    const int64_t *order;
    Py_ssize_t n_ms, n_order, most;
    long score;
    double weight;
    PlanarOutcome *outcomes;
    Py_ssize_t *seed_counts;
    int32_t *kept_pairs;
    size_t stride;   /* int32 per m in kept_pairs */
    Py_ssize_t next; /* the next m to take (atomic) */
    int failed;      /* out of memory in a worker (atomic) */
} Sweep;

/* One worker: takes the next m not yet taken until none is left. Returns NULL (pthread's type). */
static void *sweep_worker(void *argument)
{
    Sweep *sweep = argument;
    const Planar *model = sweep->model;
    int32_t n1 = model->g.n1, n2 = model->g.n2;
    int64_t cells = (int64_t)n1 * n2;
    Planar p;
    memset(&p, 0, sizeof(p));
    p.g = model->g;
    p.edges1 = model->edges1;
    p.edges2 = model->edges2;
    p.rotation_min = model->rotation_min;
    p.reflections = model->reflections;
    int32_t *seeds = malloc(sizeof(int32_t) * 2 * (size_t)(sweep->most + 1));
    int64_t *chosen = malloc(sizeof(int64_t) * (size_t)(sweep->most + 1));
    uint8_t *same = malloc((size_t)cells + 1);
    if (seeds == NULL || chosen == NULL || same == NULL || planar_alloc(&p) < 0) {
        __atomic_store_n(&sweep->failed, 1, __ATOMIC_RELAXED);
        goto done;
    }
    p.g.same = same;
    Py_ssize_t s;
    while (!__atomic_load_n(&sweep->failed, __ATOMIC_RELAXED)
           && (s = __atomic_fetch_add(&sweep->next, 1, __ATOMIC_RELAXED)) < sweep->n_ms) {
        double m = sweep->ms[s];
        /* bisect_right: the values <= m, at most the cap, then in position order. */
        Py_ssize_t low = 0, high = sweep->n_order;
        while (low < high) {
            Py_ssize_t middle = low + (high - low) / 2;
            if (m < sweep->values[middle]) {
                high = middle;
            } else {
                low = middle + 1;
            }
        }
        Py_ssize_t count = low < sweep->most ? low : sweep->most;
        sweep->seed_counts[s] = count;
        if (count == 0) {
            continue;
        }
        memcpy(chosen, sweep->order, sizeof(int64_t) * (size_t)count);
        qsort(chosen, (size_t)count, sizeof(int64_t), by_position);
        for (Py_ssize_t k = 0; k < count; k++) {
            seeds[2 * k] = (int32_t)(chosen[k] / n2);
            seeds[2 * k + 1] = (int32_t)(chosen[k] % n2);
        }
        const double *c = sweep->c;
        for (int64_t k = 0; k < cells; k++) {
            same[k] = c[k] <= m;
        }
        PairCosts costs = {c, sweep->weight, sweep->score == 2, m};
        planar_run(&p, seeds, count, sweep->score ? &costs : NULL, &sweep->outcomes[s]);
        if (p.failed) {
            __atomic_store_n(&sweep->failed, 1, __ATOMIC_RELAXED);
            break;
        }
        memcpy(sweep->kept_pairs + sweep->stride * (size_t)s, p.best_pairs,
               sizeof(int32_t) * 2 * (size_t)sweep->outcomes[s].n_pairs);
    }
done:
    free(seeds);
    free(chosen);
    free(same);
    planar_close(&p);
    return NULL;
}

/* planar_sweep(off1, nb1, off2, nb2, edges1, edges2, c, order, values, cap, ms, score, weight,
 * rotation_min, reflections, threads, table_cells) -> [(pairs, cost, structural_cost, hypotheses,
 * seeds_expanded, seeds) per m] (``table_cells``: see planar_match).
 *
 * ``c``: n1 x n2 doubles with no NaN. ``order``: positions in the flattened c (int64) sorted by
 * value, ties by position, and ``values`` their values (SeedSelector's); ``cap``: the seed cap.
 * ``ms``: the values of m (doubles). ``score``: 0 the structural cost alone, 1 plus ``weight``
 * times the sum of c over the pairs ('signature'), 2 plus ``weight`` times the pairs with c > m
 * ('substitutions'). At an m with no seed the entry is ([], None, 0, 0, 0, 0). ``threads``: how
 * many threads share the values of m (each takes the next one; each has its own scratch and an
 * n1 x n2 "same" of its own); the results do not depend on it. */
KERNEL(planar_sweep)
{
    if (check_nargs("planar_sweep", nargs, 17) < 0) {
        return NULL;
    }
    Planar p;
    Py_buffer views[8];
    int n_views = 0;
    PyObject *result = NULL;
    int32_t *kept_pairs = NULL;
    PlanarOutcome *outcomes = NULL;
    Py_ssize_t *seed_counts = NULL;
    pthread_t *workers = NULL;
    if (planar_open(&p, args, views, "planar_sweep", args[16]) < 0) {
        return NULL;
    }
    n_views = 4;
    if (get_buffer(args[6], 8, 'f', 2, "planar_sweep: c", &views[n_views]) < 0) goto done;
    const double *c = views[n_views++].buf;
    if (get_buffer(args[7], 8, 'i', 1, "planar_sweep: order", &views[n_views]) < 0) goto done;
    const int64_t *order = views[n_views++].buf;
    if (get_buffer(args[8], 8, 'f', 1, "planar_sweep: values", &views[n_views]) < 0) goto done;
    const double *values = views[n_views++].buf;
    if (get_buffer(args[10], 8, 'f', 1, "planar_sweep: ms", &views[n_views]) < 0) goto done;
    const double *ms = views[n_views++].buf;
    Py_ssize_t n_ms = views[n_views - 1].shape[0], n_order = views[n_views - 3].shape[0];
    long long cap = PyLong_AsLongLong(args[9]);
    long score = PyLong_AsLong(args[11]);
    double weight = PyFloat_AsDouble(args[12]);
    p.rotation_min = (int)PyLong_AsLong(args[13]);
    p.reflections = (int)PyLong_AsLong(args[14]);
    long threads = PyLong_AsLong(args[15]);
    if (PyErr_Occurred()) goto done;
    int32_t n1 = p.g.n1, n2 = p.g.n2;
    int64_t cells = (int64_t)n1 * n2;
    if (views[4].shape[0] != n1 || views[4].shape[1] != n2 || views[6].shape[0] != n_order || score < 0
        || score > 2 || cap < 0 || threads < 1) {
        PyErr_SetString(PyExc_ValueError, "planar_sweep: c must be n1 x n2, order and values of one length, "
                                          "score 0-2, cap >= 0, threads >= 1");
        goto done;
    }
    for (Py_ssize_t k = 0; k < n_order; k++) {
        if (order[k] < 0 || order[k] >= cells || (k > 0 && values[k] < values[k - 1])) {
            PyErr_SetString(PyExc_ValueError, "planar_sweep: order must index c and values must ascend");
            goto done;
        }
    }
    threads = threads < n_ms ? threads : (n_ms > 0 ? (long)n_ms : 1);
    size_t stride = 2 * (size_t)(p.n_min + 1);
    kept_pairs = malloc(sizeof(int32_t) * stride * (size_t)(n_ms + 1));
    outcomes = calloc((size_t)n_ms + 1, sizeof(PlanarOutcome));
    seed_counts = calloc((size_t)n_ms + 1, sizeof(Py_ssize_t));
    workers = calloc((size_t)threads, sizeof(pthread_t));
    if (kept_pairs == NULL || outcomes == NULL || seed_counts == NULL || workers == NULL) {
        PyErr_NoMemory();
        goto done;
    }
    Sweep sweep = {&p, c, values, ms, order, n_ms, n_order, n_order < cap ? n_order : (Py_ssize_t)cap,
                   score, weight, outcomes, seed_counts, kept_pairs, stride, 0, 0};
    Py_BEGIN_ALLOW_THREADS
    long started = 1; /* this thread is a worker too; a thread that cannot start leaves its share to the others */
    while (started < threads && pthread_create(&workers[started], NULL, sweep_worker, &sweep) == 0) {
        started++;
    }
    sweep_worker(&sweep);
    for (long k = 1; k < started; k++) {
        pthread_join(workers[k], NULL);
    }
    Py_END_ALLOW_THREADS
    if (sweep.failed) {
        PyErr_NoMemory();
        goto done;
    }
    result = PyList_New(n_ms);
    if (result == NULL) goto done;
    for (Py_ssize_t s = 0; s < n_ms; s++) {
        PyObject *entry;
        if (seed_counts[s] == 0) {
            entry = Py_BuildValue("([]Oiiin)", Py_None, 0, 0, 0, (Py_ssize_t)0);
        } else {
            PyObject *outcome = planar_outcome_tuple(kept_pairs + stride * (size_t)s, &outcomes[s], score != 0);
            entry = outcome == NULL ? NULL : Py_BuildValue("(OOOOOn)", PyTuple_GET_ITEM(outcome, 0),
                                                           PyTuple_GET_ITEM(outcome, 1), PyTuple_GET_ITEM(outcome, 2),
                                                           PyTuple_GET_ITEM(outcome, 3), PyTuple_GET_ITEM(outcome, 4),
                                                           seed_counts[s]);
            Py_XDECREF(outcome);
        }
        if (entry == NULL) {
            Py_CLEAR(result);
            goto done;
        }
        PyList_SET_ITEM(result, s, entry);
    }
done:
    for (int k = 0; k < n_views; k++) {
        PyBuffer_Release(&views[k]);
    }
    free(kept_pairs);
    free(outcomes);
    free(seed_counts);
    free(workers);
    planar_close(&p);
    return result;
}
