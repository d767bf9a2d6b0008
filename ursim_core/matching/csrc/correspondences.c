/* Which region of one segmentation each region of others overlaps most, in C (module
 * ``_matching_kernels``, see module.c): a port of resampling.region_correspondences.
 *
 * NumPy found the pixels inside a region once, then gathered them from each other segmentation
 * and made a joint histogram by a bincount, with temporaries the size of those pixels. Here one
 * pass over the labels finds the stretches of pixels inside a region, and each other
 * segmentation's histogram is counted over them by runs (round 41: 7.8 -> 2.4 ms for the
 * segmentations of a turned KTH sketch). */
#include "kernels.h"

#include <stdlib.h>

static int is_int32(const Py_buffer *view)
{
    const char *format = view->format ? view->format : "B";
    while (*format == '<' || *format == '=' || *format == '@') {
        format++;
    }
    return view->itemsize == 4 && (*format == 'i' || *format == 'l');
}

/* region_correspondences(labels, others, largest): labels and each of others are C-contiguous
 * int32 arrays of one size; returns one dict per other ({their region: our region}, their
 * regions ascending, ours the first of the largest counts: ties to the lower id), or None when
 * a histogram would have more than ``largest`` cells (Python counts then). */
KERNEL(region_correspondences)
{
    (void)self;
    if (check_nargs("region_correspondences", nargs, 3) < 0) {
        return NULL;
    }
    PyObject *others = PySequence_Fast(args[1], "others must be a sequence");
    if (others == NULL) {
        return NULL;
    }
    long long largest = PyLong_AsLongLong(args[2]);
    if (largest == -1 && PyErr_Occurred()) {
        Py_DECREF(others);
        return NULL;
    }
    Py_ssize_t n_others = PySequence_Fast_GET_SIZE(others);
    Py_buffer ours_view;
    Py_buffer *views = calloc((size_t)(n_others > 0 ? n_others : 1), sizeof(Py_buffer));
    int32_t *highest = calloc((size_t)(n_others > 0 ? n_others : 1), sizeof(int32_t));
    int64_t **counts = calloc((size_t)(n_others > 0 ? n_others : 1), sizeof(int64_t *));
    PyObject *found = NULL;
    Py_ssize_t *spans = NULL; /* [first, end) of each stretch of pixels inside our regions */
    Py_ssize_t n_views = 0;
    int have_ours = 0;
    if (views == NULL || highest == NULL || counts == NULL) {
        PyErr_NoMemory();
        goto done;
    }
    if (PyObject_GetBuffer(args[0], &ours_view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) {
        goto done;
    }
    have_ours = 1;
    if (!is_int32(&ours_view)) {
        PyErr_SetString(PyExc_TypeError, "labels must be a C-contiguous int32 array");
        goto done;
    }
    Py_ssize_t n = ours_view.len / 4;
    const int32_t *ours = ours_view.buf;
    for (Py_ssize_t k = 0; k < n_others; k++) {
        if (PyObject_GetBuffer(PySequence_Fast_GET_ITEM(others, k), &views[k], PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) {
            goto done;
        }
        n_views += 1;
        if (!is_int32(&views[k]) || views[k].len != ours_view.len) {
            PyErr_SetString(PyExc_TypeError, "every other segmentation must be int32, of the labels' size");
            goto done;
        }
    }
    /* The stretches of consecutive pixels inside a region of ours (about a fifth of a turned
     * sketch's image), found once for every other segmentation. */
    int64_t stride = 1; /* our highest region + 1 (int64: a region id may be INT32_MAX) */
    Py_ssize_t n_spans = 0, room = 64;
    spans = malloc((size_t)room * 2 * sizeof(Py_ssize_t));
    if (spans == NULL) {
        PyErr_NoMemory();
        goto done;
    }
    for (Py_ssize_t i = 0; i < n;) {
        if (ours[i] <= 0) {
            i += 1;
            continue;
        }
        Py_ssize_t first = i;
        while (i < n && ours[i] > 0) {
            stride = ours[i] >= stride ? (int64_t)ours[i] + 1 : stride;
            i += 1;
        }
        if (n_spans == room) {
            room *= 2;
            Py_ssize_t *grown = realloc(spans, (size_t)room * 2 * sizeof(Py_ssize_t));
            if (grown == NULL) {
                PyErr_NoMemory();
                goto done;
            }
            spans = grown;
        }
        spans[2 * n_spans] = first, spans[2 * n_spans + 1] = i;
        n_spans += 1;
    }
    for (Py_ssize_t k = 0; k < n_others; k++) {
        const int32_t *theirs = views[k].buf;
        int32_t top = 0;
        for (Py_ssize_t span = 0; span < n_spans; span++) {
            for (Py_ssize_t i = spans[2 * span]; i < spans[2 * span + 1]; i++) {
                top = theirs[i] > top ? theirs[i] : top;
            }
        }
        highest[k] = top;
        if (((int64_t)top + 1) * stride > largest) {
            Py_INCREF(Py_None);
            found = Py_None;
            goto done;
        }
        int64_t *count = counts[k] = calloc((size_t)(top + 1) * (size_t)stride, sizeof(int64_t));
        if (count == NULL) {
            PyErr_NoMemory();
            goto done;
        }
        /* Counted by runs of one (their, our) pair: adding 1 pixel by pixel to one cell makes
         * every addition wait for the one before. */
        for (Py_ssize_t span = 0; span < n_spans; span++) {
            Py_ssize_t i = spans[2 * span], end = spans[2 * span + 1];
            while (i < end) {
                int32_t our = ours[i], their = theirs[i];
                Py_ssize_t first = i;
                while (i < end && ours[i] == our && theirs[i] == their) {
                    i += 1;
                }
                if (their > 0) {
                    count[(int64_t)their * stride + our] += i - first;
                }
            }
        }
    }
    found = PyList_New(n_others);
    if (found == NULL) {
        goto done;
    }
    for (Py_ssize_t k = 0; k < n_others; k++) {
        PyObject *carried = PyDict_New();
        if (carried == NULL) {
            Py_CLEAR(found);
            goto done;
        }
        PyList_SET_ITEM(found, k, carried);
        for (int32_t their = 1; their <= highest[k]; their++) {
            const int64_t *row = counts[k] + (int64_t)their * stride;
            int64_t best = -1;
            int64_t most = 0;
            for (int64_t our = 0; our < stride; our++) {
                if (row[our] > most) {
                    most = row[our];
                    best = our;
                }
            }
            if (best < 0) {
                continue;
            }
            PyObject *key = PyLong_FromLong(their), *value = PyLong_FromLongLong(best);
            int failed = key == NULL || value == NULL || PyDict_SetItem(carried, key, value) < 0;
            Py_XDECREF(key);
            Py_XDECREF(value);
            if (failed) {
                Py_CLEAR(found);
                goto done;
            }
        }
    }
done:
    if (counts != NULL) {
        for (Py_ssize_t k = 0; k < n_others; k++) {
            free(counts[k]);
        }
    }
    for (Py_ssize_t k = 0; k < n_views; k++) {
        PyBuffer_Release(&views[k]);
    }
    if (have_ours) {
        PyBuffer_Release(&ours_view);
    }
    free(views), free(highest), free(counts), free(spans);
    Py_DECREF(others);
    return found;
}
