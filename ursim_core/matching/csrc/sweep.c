/* The planar matcher over a sweep of m in one call (module ``_matching_kernels``, see module.c).
 *
 * What ursim_core/matching/single.py's match_at does at each m, for the C loop's case: the seeds
 * of SeedSelector.at(m) (the ``cap`` lowest pairs of c, ties by position, in position order), the
 * relation ``c <= m``, the pair costs of the hypothesis score, and planar_run. The automatic m
 * matches a turned KTH sketch at about 600 values of m; a call per m spent more in Python around
 * the loop than in it.
 */
#include "kernels.h"

#include <stdlib.h>
#include <string.h>

static int by_position(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

/* planar_sweep(off1, nb1, off2, nb2, edges1, edges2, c, order, values, cap, ms, score, weight,
 * rotation_min, reflections) -> [(pairs, cost, structural_cost, hypotheses, seeds_expanded,
 * seeds) per m].
 *
 * ``c``: n1 x n2 doubles with no NaN. ``order``: positions in the flattened c (int64) sorted by
 * value, ties by position, and ``values`` their values (SeedSelector's); ``cap``: the seed cap.
 * ``ms``: the values of m (doubles). ``score``: 0 the structural cost alone, 1 plus ``weight``
 * times the sum of c over the pairs ('signature'), 2 plus ``weight`` times the pairs with c > m
 * ('substitutions'). At an m with no seed the entry is ([], None, 0, 0, 0, 0). */
KERNEL(planar_sweep)
{
    if (check_nargs("planar_sweep", nargs, 15) < 0) {
        return NULL;
    }
    Planar p;
    Py_buffer views[8];
    int n_views = 0;
    PyObject *result = NULL;
    int32_t *seeds = NULL, *kept_pairs = NULL;
    int64_t *chosen = NULL;
    uint8_t *same = NULL;
    double *substituted = NULL;
    PlanarOutcome *outcomes = NULL;
    Py_ssize_t *seed_counts = NULL;
    if (planar_open(&p, args, views, "planar_sweep") < 0) {
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
    if (PyErr_Occurred()) goto done;
    int32_t n1 = p.g.n1, n2 = p.g.n2;
    int64_t cells = (int64_t)n1 * n2;
    if (views[4].shape[0] != n1 || views[4].shape[1] != n2 || views[6].shape[0] != n_order || score < 0
        || score > 2 || cap < 0) {
        PyErr_SetString(PyExc_ValueError,
                        "planar_sweep: c must be n1 x n2, order and values of one length, score 0-2, cap >= 0");
        goto done;
    }
    for (Py_ssize_t k = 0; k < n_order; k++) {
        if (order[k] < 0 || order[k] >= cells || (k > 0 && values[k] < values[k - 1])) {
            PyErr_SetString(PyExc_ValueError, "planar_sweep: order must index c and values must ascend");
            goto done;
        }
    }
    Py_ssize_t most = n_order < cap ? n_order : (Py_ssize_t)cap;
    seeds = malloc(sizeof(int32_t) * 2 * (size_t)(most + 1));
    chosen = malloc(sizeof(int64_t) * (size_t)(most + 1));
    same = malloc((size_t)cells + 1);
    substituted = score == 2 ? malloc(sizeof(double) * (size_t)(cells + 1)) : NULL;
    kept_pairs = malloc(sizeof(int32_t) * 2 * (size_t)(p.n_min + 1) * (size_t)(n_ms + 1));
    outcomes = calloc((size_t)n_ms + 1, sizeof(PlanarOutcome));
    seed_counts = calloc((size_t)n_ms + 1, sizeof(Py_ssize_t));
    if (seeds == NULL || chosen == NULL || same == NULL || (score == 2 && substituted == NULL) || kept_pairs == NULL
        || outcomes == NULL || seed_counts == NULL) {
        PyErr_NoMemory();
        goto done;
    }
    p.g.same = same;
    const double *costs = score == 1 ? c : substituted;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t s = 0; s < n_ms; s++) {
        double m = ms[s];
        /* bisect_right: the values <= m, at most the cap, then in position order. */
        Py_ssize_t low = 0, high = n_order;
        while (low < high) {
            Py_ssize_t middle = low + (high - low) / 2;
            if (m < values[middle]) {
                high = middle;
            } else {
                low = middle + 1;
            }
        }
        Py_ssize_t count = low < most ? low : most;
        seed_counts[s] = count;
        if (count == 0) {
            continue;
        }
        memcpy(chosen, order, sizeof(int64_t) * (size_t)count);
        qsort(chosen, (size_t)count, sizeof(int64_t), by_position);
        for (Py_ssize_t k = 0; k < count; k++) {
            seeds[2 * k] = (int32_t)(chosen[k] / n2);
            seeds[2 * k + 1] = (int32_t)(chosen[k] % n2);
        }
        for (int64_t k = 0; k < cells; k++) {
            same[k] = c[k] <= m;
        }
        if (score == 2) {
            for (int64_t k = 0; k < cells; k++) {
                substituted[k] = c[k] > m ? 1.0 : 0.0;
            }
        }
        planar_run(&p, seeds, count, score ? costs : NULL, weight, &outcomes[s]);
        memcpy(kept_pairs + 2 * (size_t)(p.n_min + 1) * (size_t)s, p.best_pairs,
               sizeof(int32_t) * 2 * (size_t)outcomes[s].n_pairs);
    }
    Py_END_ALLOW_THREADS
    result = PyList_New(n_ms);
    if (result == NULL) goto done;
    for (Py_ssize_t s = 0; s < n_ms; s++) {
        PyObject *entry;
        if (seed_counts[s] == 0) {
            entry = Py_BuildValue("([]Oiiin)", Py_None, 0, 0, 0, (Py_ssize_t)0);
        } else {
            PyObject *outcome = planar_outcome_tuple(kept_pairs + 2 * (size_t)(p.n_min + 1) * (size_t)s, &outcomes[s],
                                                     score != 0);
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
    free(seeds);
    free(chosen);
    free(same);
    free(substituted);
    free(kept_pairs);
    free(outcomes);
    free(seed_counts);
    planar_close(&p);
    return result;
}
