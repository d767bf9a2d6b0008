/* The matcher's C kernels (module.c lists them), each a METH_FASTCALL function of the module
 * ``_matching_kernels`` built by ursim_core.matching.kernels. */
#ifndef URSIM_MATCHING_KERNELS_H
#define URSIM_MATCHING_KERNELS_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>

#define KERNEL(name) PyObject *kernel_##name(PyObject *self, PyObject *const *args, Py_ssize_t nargs)

/* 0, or -1 with a TypeError naming the kernel when it was given another number of arguments. */
static inline int check_nargs(const char *name, Py_ssize_t nargs, Py_ssize_t expected)
{
    if (nargs != expected) {
        PyErr_Format(PyExc_TypeError, "%s takes %zd arguments (%zd given)", name, expected, nargs);
        return -1;
    }
    return 0;
}

/* A C-contiguous buffer of a given item size and format kind ('i' signed int, 'f' float, 'b' bool/uint8). */
static inline int get_buffer(PyObject *obj, Py_ssize_t itemsize, char kind, int ndim, const char *what, Py_buffer *view)
{
    if (PyObject_GetBuffer(obj, view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) {
        PyErr_Format(PyExc_TypeError, "%s must be a C-contiguous array", what);
        return -1;
    }
    const char *format = view->format ? view->format : "B";
    while (*format == '<' || *format == '=' || *format == '@' || *format == '|') {
        format++;
    }
    int kind_ok = (kind == 'i' && (*format == 'i' || *format == 'l' || *format == 'q'))
                  || (kind == 'f' && *format == 'd') || (kind == 'b' && (*format == '?' || *format == 'B'));
    if (view->itemsize != itemsize || !kind_ok || view->ndim != ndim) {
        PyErr_Format(PyExc_TypeError, "%s has the wrong type or shape (format %s, %d dimensions)", what,
                     view->format ? view->format : "B", view->ndim);
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

/* Reverse the order of ``count`` (first, second) pairs in ``out``: the alignments' backtraces
 * (planar.c's table, bitalign.c's bit-parallel one) find the last pair first. */
static inline void reverse_pairs(int32_t *out, int32_t count)
{
    for (int32_t k = 0; k < count / 2; k++) {
        int32_t x = out[2 * k], y = out[2 * k + 1];
        out[2 * k] = out[2 * (count - 1 - k)];
        out[2 * k + 1] = out[2 * (count - 1 - k) + 1];
        out[2 * (count - 1 - k)] = x;
        out[2 * (count - 1 - k) + 1] = y;
    }
}

/* planar.c: the seed-and-expand loop, shared by planar_match and planar_sweep (sweep.c). */
typedef struct {
    int32_t n1, n2;
    const int32_t *off1, *nb1, *off2, *nb2; /* cyclic neighbour orders (CSR) */
    const uint8_t *same;                    /* n1 x n2: c <= m */
    int64_t table_cells;                    /* alignments of more cells ((rows + 1) x (cols + 1)) are
                                             * bit-parallel (bitalign.c), the others fill ``table`` */
    int32_t *table;
    int32_t *row_buffer;                    /* a rotated or reversed first sequence */
} Graphs;

/* bitalign.c: the "same" bits of a sketch vertex's neighbour order (reversed when ``reflected``)
 * against a metric vertex's, packed once per match (edit_kernel.pack_same's layout). */
typedef struct {
    int32_t v, w, reflected, size1, size2, words;
    uint64_t *bits; /* size2 rows of ``words``: bit p of row q is same[order1[p % size1]][order2[q]] */
} PackedOrders;

/* bitalign.c: the aligned pairs of an arc pair of packed orders, remembered for the match. */
typedef struct {
    int32_t key[7]; /* v, w, reflected, start1, rows, start2, cols; rows 0: an empty slot */
    int32_t count;
    size_t offset; /* in ``arena`` */
} ArcEntry;

typedef struct {
    Graphs g;
    int64_t edges1, edges2;
    int rotation_min, reflections;
    int failed; /* set when memory ran out inside planar_run (which holds no GIL to raise) */
    int32_t n_min, stamp;
    int32_t *work, *stamps; /* scratch; stamps: seen in the sketch, matched in the sketch, seen in the metric map */
    uint8_t *consumed;      /* n1 x n2 bits: seeds no longer starting a hypothesis */
    int32_t *arc1, *arc2, *locks, *aligned, *queue, *pairs, *best_pairs, *partner;
    int32_t *where2; /* n2: 1 + the position of a metric vertex in the popped pair's order, else 0 */
    /* bitalign.c's state, emptied by bit_reset at the start of every match */
    PackedOrders *packs;
    int32_t n_packs, packs_capacity;
    size_t pack_words;
    uint64_t *deltas; /* the columns' +-1 differences of one alignment, for its backtrace */
    size_t deltas_words;
    ArcEntry *arcs;
    size_t n_arcs, arcs_capacity;
    int32_t *arena;
    size_t arena_used, arena_capacity;
} Planar;

typedef struct {
    int32_t n_pairs;
    int64_t structure, hypotheses, expanded;
    double cost;
} PlanarOutcome;

/* Pair costs of a match: none, ``cost[k]`` of an n1 x n2 matrix, or ``cost[k] > above`` as 1 or 0
 * (the 'substitutions' score, without an n1 x n2 matrix of its own). */
typedef struct {
    const double *cost;
    double weight;
    int substitutions;
    double above;
} PairCosts;

int planar_open(Planar *p, PyObject *const *args, Py_buffer *views, const char *name, PyObject *table_cells);
int planar_alloc(Planar *p);
void planar_close(Planar *p);
void planar_run(Planar *p, const int32_t *seeds, Py_ssize_t n_seeds, const PairCosts *costs, PlanarOutcome *out);
PyObject *planar_outcome_tuple(const int32_t *pairs, const PlanarOutcome *outcome, int weighted);

/* bitalign.c */
void bit_reset(Planar *p);
void bit_free(Planar *p);
int32_t bit_seed_pairs(Planar *p, int32_t v, int32_t w, int rotation_min, int reflections, int *reflected,
                       int32_t *out);
const int32_t *bit_arc_pairs(Planar *p, int32_t v, int32_t w, int reflected, int32_t start1, int32_t rows,
                             int32_t start2, int32_t cols, int32_t *count);

KERNEL(planar_match);
/* sweep.c */
KERNEL(planar_sweep);
/* refit.c */
KERNEL(fit_axes);
/* overlap.c */
KERNEL(overlap_search);
/* correspondences.c */
KERNEL(region_correspondences);

#endif
