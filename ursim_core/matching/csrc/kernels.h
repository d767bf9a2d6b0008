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

/* planar.c: the seed-and-expand loop, shared by planar_match and planar_sweep (sweep.c). */
typedef struct {
    int32_t n1, n2;
    const int32_t *off1, *nb1, *off2, *nb2; /* cyclic neighbour orders (CSR) */
    const uint8_t *same;                    /* n1 x n2: c <= m */
    int32_t *table;                         /* edit-distance table, (max degree 1 + 1) x (max degree 2 + 1) */
    int32_t *row_buffer;                    /* a rotated or reversed first sequence */
} Graphs;

typedef struct {
    Graphs g;
    int64_t edges1, edges2;
    int rotation_min, reflections;
    int32_t n_min, stamp;
    int32_t *work, *stamps; /* scratch; stamps: seen in the sketch, matched in the sketch, seen in the metric map */
    uint8_t *consumed;      /* n1 x n2: seeds no longer starting a hypothesis */
    int32_t *arc1, *arc2, *locks, *aligned, *queue, *pairs, *best_pairs, *partner;
} Planar;

typedef struct {
    int32_t n_pairs;
    int64_t structure, hypotheses, expanded;
    double cost;
} PlanarOutcome;

int planar_open(Planar *p, PyObject *const *args, Py_buffer *views, const char *name);
void planar_close(Planar *p);
void planar_run(Planar *p, const int32_t *seeds, Py_ssize_t n_seeds, const double *costs, double weight,
                PlanarOutcome *out);
PyObject *planar_outcome_tuple(const int32_t *pairs, const PlanarOutcome *outcome, int weighted);

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
