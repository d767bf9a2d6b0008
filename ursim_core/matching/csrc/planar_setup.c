/* What planar_match (planar.c) and planar_sweep (sweep.c) share around the loop: reading the
 * neighbour orders, the loop's scratch, and the outcome as Python values. */
#include "kernels.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Read the neighbour orders and options shared by planar_match and planar_sweep (arguments 0-5:
 * off1, nb1, off2, nb2, edges1, edges2; and the largest table, in cells) and allocate the loop's
 * scratch. ``views`` receives the four order buffers. Returns 0, or -1 with an exception set (the
 * views taken are released). */
int planar_open(Planar *p, PyObject *const *args, Py_buffer *views, const char *name, PyObject *table_cells)
{
    memset(p, 0, sizeof(*p));
    p->g.table_cells = PyLong_AsLongLong(table_cells);
    if (PyErr_Occurred() || p->g.table_cells < 0) {
        if (!PyErr_Occurred()) {
            PyErr_Format(PyExc_ValueError, "%s: table_cells must be >= 0", name);
        }
        return -1;
    }
    const char *what[4] = {"off1", "nb1", "off2", "nb2"};
    char label[64];
    for (int k = 0; k < 4; k++) {
        snprintf(label, sizeof(label), "%s: %s", name, what[k]);
        if (get_buffer(args[k], 4, 'i', 1, label, &views[k]) < 0) {
            for (int done = 0; done < k; done++) {
                PyBuffer_Release(&views[done]);
            }
            return -1;
        }
    }
    p->edges1 = PyLong_AsLongLong(args[4]);
    p->edges2 = PyLong_AsLongLong(args[5]);
    Graphs *g = &p->g;
    g->n1 = (int32_t)(views[0].shape[0] - 1);
    g->n2 = (int32_t)(views[2].shape[0] - 1);
    g->off1 = views[0].buf;
    g->nb1 = views[1].buf;
    g->off2 = views[2].buf;
    g->nb2 = views[3].buf;
    int32_t n1 = g->n1, n2 = g->n2;
    if (PyErr_Occurred() || n1 < 0 || n2 < 0) {
        if (!PyErr_Occurred()) {
            PyErr_Format(PyExc_ValueError, "%s: empty offsets", name);
        }
        goto fail;
    }
    if (planar_alloc(p) < 0) {
        PyErr_NoMemory();
        goto fail;
    }
    return 0;
fail:
    planar_close(p);
    for (int k = 0; k < 4; k++) {
        PyBuffer_Release(&views[k]);
    }
    return -1;
}

/* The loop's scratch for the graphs of ``p->g`` (no Python: a sweep's threads call it too).
 * Returns 0, or -1 when out of memory (what was allocated is freed by planar_close). */
int planar_alloc(Planar *p)
{
    Graphs *g = &p->g;
    int32_t n1 = g->n1, n2 = g->n2;
    int32_t degree1 = 0, degree2 = 0;
    for (int32_t v = 0; v < n1; v++) {
        int32_t d = g->off1[v + 1] - g->off1[v];
        degree1 = d > degree1 ? d : degree1;
    }
    for (int32_t v = 0; v < n2; v++) {
        int32_t d = g->off2[v + 1] - g->off2[v];
        degree2 = d > degree2 ? d : degree2;
    }
    int32_t n_min = n1 < n2 ? n1 : n2;
    int32_t d_max = degree1 > degree2 ? degree1 : degree2;
    /* Scratch: table, row buffer, two arcs, locks (2 per), aligned pairs (2 per), queue and pairs
     * (2 per, at most n1 + 1 each), the best pairs, the partners. The table holds the alignments
     * of at most g->table_cells cells; longer ones are bit-parallel (bitalign.c). */
    size_t table_cells = (size_t)(degree1 + 1) * (size_t)(degree2 + 1);
    table_cells = table_cells < (size_t)g->table_cells ? table_cells : (size_t)g->table_cells;
    size_t words = table_cells + 3 * (size_t)(d_max + 1) + 4 * (size_t)(d_max + 1)
                   + 2 * 2 * (size_t)(n1 + 2) + 2 * (size_t)(n_min + 1) + (size_t)n1;
    p->work = malloc(sizeof(int32_t) * words);
    p->stamps = calloc((size_t)(2 * n1 + n2 + 1), sizeof(int32_t));
    p->where2 = calloc((size_t)n2 + 1, sizeof(int32_t));
    p->consumed = malloc(((size_t)n1 * (size_t)n2 + 7) / 8 + 1);
    if (p->work == NULL || p->stamps == NULL || p->where2 == NULL || p->consumed == NULL) {
        return -1;
    }
    g->table = p->work;
    g->row_buffer = g->table + table_cells;
    p->arc1 = g->row_buffer + (d_max + 1);
    p->arc2 = p->arc1 + (d_max + 1);
    p->locks = p->arc2 + (d_max + 1);
    p->aligned = p->locks + 2 * (d_max + 1);
    p->queue = p->aligned + 2 * (d_max + 1);
    p->pairs = p->queue + 2 * (n1 + 2);
    p->best_pairs = p->pairs + 2 * (n1 + 2);
    p->partner = p->best_pairs + 2 * (n_min + 1);
    p->n_min = n_min;
    return 0;
}

void planar_close(Planar *p)
{
    free(p->work);
    free(p->stamps);
    free(p->where2);
    free(p->consumed);
    p->work = NULL;
    p->stamps = NULL;
    p->where2 = NULL;
    p->consumed = NULL;
    bit_free(p);
}

/* (pairs, cost, structural_cost, hypotheses, seeds_expanded) of an outcome whose pairs are
 * ``pairs``; the cost is the structural cost, an int, when not weighted (as planar.py's). */
PyObject *planar_outcome_tuple(const int32_t *pairs, const PlanarOutcome *outcome, int weighted)
{
    PyObject *listed = PyList_New(outcome->n_pairs);
    if (listed == NULL) {
        return NULL;
    }
    for (int32_t q = 0; q < outcome->n_pairs; q++) {
        PyObject *pair = Py_BuildValue("(ii)", pairs[2 * q], pairs[2 * q + 1]);
        if (pair == NULL) {
            Py_DECREF(listed);
            return NULL;
        }
        PyList_SET_ITEM(listed, q, pair);
    }
    PyObject *cost = weighted ? PyFloat_FromDouble(outcome->cost) : PyLong_FromLongLong((long long)outcome->structure);
    if (cost == NULL) {
        Py_DECREF(listed);
        return NULL;
    }
    return Py_BuildValue("(NNLLL)", listed, cost, (long long)outcome->structure, (long long)outcome->hypotheses,
                         (long long)outcome->expanded);
}
