/* What every MAORIS kernel in C shares: the Python and numpy headers, reading the arguments
 * of a kernel (arrays, tuples, integers) with the checks numba's typed signatures made,
 * making the arrays it returns, and the small helpers of ../kernels/helpers.py.
 *
 * The C kernels are a port of the numba kernels of ../kernels (the reference: a test checks
 * that both give the same label images). The semantics that differ between numba and C are
 * spelled out where they matter: numba's // and % floor (C truncates: use floor_div and
 * floor_mod on values that can be negative), a negative index wraps around in numba (C reads
 * before the array), and numba computes integer expressions in 64 bits.
 */
#ifndef URSIM_MAORIS_COMMON_H
#define URSIM_MAORIS_COMMON_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#define NPY_NO_DEPRECATED_API NPY_1_22_API_VERSION
#define PY_ARRAY_UNIQUE_SYMBOL ursim_maoris_ARRAY_API
#ifndef URSIM_MAORIS_MODULE_C
#define NO_IMPORT_ARRAY
#endif
#include <numpy/arrayobject.h>

#include <pthread.h>
#include <sched.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

/* A C-contiguous array argument: its data, length (all elements) and shape. */
typedef struct {
    PyArrayObject *array; /* borrowed */
    void *data;
    npy_intp size;        /* number of elements */
    npy_intp rows, cols;  /* shape of a 2-D array (rows = size, cols = 1 for 1-D) */
    npy_intp row_stride, col_stride; /* in elements, for the one strided argument type */
} Array;

/* Read argument ``obj`` (named ``what`` in errors) as a writeable array of ``typenum`` with
 * ``ndim`` dimensions; C-contiguous unless ``any_layout``. Returns 0, or -1 with a TypeError
 * set, as a call of the numba kernel with another type would have raised. */
static inline int array_arg(PyObject *obj, int typenum, int ndim, int any_layout, const char *what, Array *out)
{
    if (!PyArray_Check(obj)) {
        PyErr_Format(PyExc_TypeError, "%s: expected a numpy array, got %s", what, Py_TYPE(obj)->tp_name);
        return -1;
    }
    PyArrayObject *array = (PyArrayObject *)obj;
    if (PyArray_TYPE(array) != typenum || PyArray_NDIM(array) != ndim) {
        PyErr_Format(PyExc_TypeError, "%s: expected a %d-D array of type %d, got %d-D of type %d", what, ndim,
                     typenum, PyArray_NDIM(array), PyArray_TYPE(array));
        return -1;
    }
    if (!PyArray_ISWRITEABLE(array) || !PyArray_ISALIGNED(array) || PyArray_ISBYTESWAPPED(array)) {
        PyErr_Format(PyExc_TypeError, "%s: the array must be writeable, aligned and in native byte order", what);
        return -1;
    }
    if (!any_layout && !PyArray_IS_C_CONTIGUOUS(array)) {
        PyErr_Format(PyExc_TypeError, "%s: the array must be C-contiguous", what);
        return -1;
    }
    npy_intp item = PyArray_ITEMSIZE(array);
    out->array = array;
    out->data = PyArray_DATA(array);
    out->size = PyArray_SIZE(array);
    out->rows = ndim >= 1 ? PyArray_DIM(array, 0) : 1;
    out->cols = ndim >= 2 ? PyArray_DIM(array, 1) : 1;
    out->row_stride = ndim >= 1 ? PyArray_STRIDE(array, 0) / item : 1;
    out->col_stride = ndim >= 2 ? PyArray_STRIDE(array, 1) / item : 1;
    return 0;
}

/* The items of tuple argument ``obj`` of exactly ``n`` items (borrowed), or NULL with a TypeError. */
static inline PyObject *const *tuple_arg(PyObject *obj, Py_ssize_t n, const char *what)
{
    if (!PyTuple_Check(obj) || PyTuple_GET_SIZE(obj) != n) {
        PyErr_Format(PyExc_TypeError, "%s: expected a tuple of %zd items", what, n);
        return NULL;
    }
    return &PyTuple_GET_ITEM(obj, 0);
}

/* An int64 argument (a Python or numpy integer); -1 with an error set when it is none. */
static inline int int_arg(PyObject *obj, const char *what, int64_t *out)
{
    if (PyFloat_Check(obj)) {
        PyErr_Format(PyExc_TypeError, "%s: expected an integer, got a float", what);
        return -1;
    }
    long long value = PyLong_AsLongLong(obj);
    if (value == -1 && PyErr_Occurred()) {
        return -1;
    }
    *out = (int64_t)value;
    return 0;
}

/* A float64 argument (any real number). */
static inline int float_arg(PyObject *obj, const char *what, double *out)
{
    double value = PyFloat_AsDouble(obj);
    if (value == -1.0 && PyErr_Occurred()) {
        PyErr_Format(PyExc_TypeError, "%s: expected a real number", what);
        return -1;
    }
    *out = value;
    return 0;
}

/* ValueError "KERNEL: FIRST and SECOND differ in shape" unless the 2-D arrays ``a`` and ``b``
 * have the same rows and columns. 0, or -1 with the error set. */
static inline int check_same_shape(const char *kernel, const char *first, const Array *a, const char *second,
                                   const Array *b)
{
    if (a->rows != b->rows || a->cols != b->cols) {
        PyErr_Format(PyExc_ValueError, "%s: %s and %s differ in shape", kernel, first, second);
        return -1;
    }
    return 0;
}

/* Check a fast call's argument count. */
static inline int check_nargs(const char *kernel, Py_ssize_t nargs, Py_ssize_t wanted)
{
    if (nargs != wanted) {
        PyErr_Format(PyExc_TypeError, "%s() takes %zd arguments (%zd given)", kernel, wanted, nargs);
        return -1;
    }
    return 0;
}

/* A new C-contiguous 1-D or 2-D array (uninitialised; NULL with MemoryError). Call with the GIL. */
static inline PyArrayObject *new_array_1d(npy_intp n, int typenum)
{
    npy_intp dims[1] = {n};
    return (PyArrayObject *)PyArray_SimpleNew(1, dims, typenum);
}

static inline PyArrayObject *new_array_2d(npy_intp rows, npy_intp cols, int typenum)
{
    npy_intp dims[2] = {rows, cols};
    return (PyArrayObject *)PyArray_SimpleNew(2, dims, typenum);
}

static void free_capsule(PyObject *capsule)
{
    free(PyCapsule_GetPointer(capsule, "ursim_maoris_buffer"));
}

/* A numpy array that owns ``buffer`` (from malloc/realloc; freed with the array), for results
 * whose size is known only at the end of a kernel run without the GIL. On failure the buffer
 * is freed and NULL returned with an error set. ``buffer`` may be NULL when the size is 0. */
static inline PyObject *array_owning(void *buffer, int ndim, const npy_intp *dims, int typenum)
{
    if (buffer == NULL) {
        buffer = malloc(1);
        if (buffer == NULL) {
            return PyErr_NoMemory();
        }
    }
    PyObject *array = PyArray_SimpleNewFromData(ndim, (npy_intp *)dims, typenum, buffer);
    if (array == NULL) {
        free(buffer);
        return NULL;
    }
    PyObject *capsule = PyCapsule_New(buffer, "ursim_maoris_buffer", free_capsule);
    if (capsule == NULL) {
        Py_DECREF(array); /* the array does not own the buffer yet */
        free(buffer);
        return NULL;
    }
    if (PyArray_SetBaseObject((PyArrayObject *)array, capsule) < 0) {
        Py_DECREF(array);
        return NULL; /* the capsule was released, and freed the buffer */
    }
    return array;
}

/* numba's // and % on signed integers (Python's: rounded towards minus infinity). */
static inline int64_t floor_div(int64_t a, int64_t b)
{
    int64_t q = a / b;
    return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

static inline int64_t floor_mod(int64_t a, int64_t b)
{
    int64_t r = a % b;
    return (r != 0 && ((r < 0) != (b < 0))) ? r + b : r;
}

/* Ask the CPU to start loading the cache line of ``address`` (helpers._prefetch: read, keep in
 * every level). A hint only: never faults. */
#define PREFETCH(address) __builtin_prefetch((const void *)(address), 0, 3)

/* helpers._zone_of: the current zone of an original label (union-find root, path halving). */
static inline int64_t zone_of(int64_t label, int32_t *parent)
{
    while (parent[label] != label) {
        parent[label] = parent[parent[label]];
        label = parent[label];
    }
    return label;
}

/* helpers._bits: log2 of a power of two. */
static inline int64_t bits_of(int64_t size)
{
    int64_t bits = 0;
    while (((int64_t)1 << bits) < size) {
        bits += 1;
    }
    return bits;
}

/* helpers._filled / _grown for the arrays a kernel keeps to itself: malloc'd, NULL when out of
 * memory (the kernel then returns a MemoryError once it holds the GIL again). */
static inline int64_t *filled_i64(int64_t size, int64_t fill)
{
    int64_t *array = malloc((size_t)(size > 0 ? size : 1) * sizeof(int64_t));
    if (array != NULL) {
        for (int64_t i = 0; i < size; i++) {
            array[i] = fill;
        }
    }
    return array;
}

static inline int32_t *filled_i32(int64_t size, int32_t fill)
{
    int32_t *array = malloc((size_t)(size > 0 ? size : 1) * sizeof(int32_t));
    if (array != NULL) {
        for (int64_t i = 0; i < size; i++) {
            array[i] = fill;
        }
    }
    return array;
}

/* Faulting in a large fresh array on another thread while the kernel does other work
 * (MADV_POPULATE_WRITE, Linux 5.14+; elsewhere, or when it fails, nothing is done). The first
 * write to each page of a fresh array costs a page fault, and on a virtual machine whose host
 * takes back freed memory a fault costs about a microsecond per 4 KB: at 8000 x 8000 px the
 * zone graph's arrays alone (500 MB) took most of a second of faults on the kernel's thread.
 * Populating keeps the contents, so it may overlap the kernel's own writes. Only for arrays the
 * kernel writes whole (it would otherwise make resident what is never used). */
typedef struct {
    char *start;
    size_t length;
    pthread_t thread;
    int running;
} Prefault;

#define PREFAULT_MIN_BYTES ((size_t)16 << 20)

static void *prefault_run(void *arg)
{
#ifdef MADV_POPULATE_WRITE
    Prefault *job = arg;
    const size_t chunk = (size_t)8 << 20;
    for (size_t offset = 0; offset < job->length; offset += chunk) {
        size_t length = job->length - offset < chunk ? job->length - offset : chunk;
        if (madvise(job->start + offset, length, MADV_POPULATE_WRITE) != 0) {
            break; /* not supported by this kernel, or out of memory: the kernel's writes fault */
        }
    }
#else
    (void)arg;
#endif
    return NULL;
}

/* Ask for transparent huge pages for a large malloc'd block, as numpy does for its arrays:
 * one fault per 2 MB rather than per 4 KB (a hint; nothing changes where they are off). */
static inline void advise_huge_pages(void *data, size_t bytes)
{
#ifdef MADV_HUGEPAGE
    const uintptr_t huge = (uintptr_t)1 << 21;
    uintptr_t first = ((uintptr_t)data + huge - 1) & ~(huge - 1), end = ((uintptr_t)data + bytes) & ~(huge - 1);
    if (end > first) {
        madvise((void *)first, end - first, MADV_HUGEPAGE);
    }
#else
    (void)data, (void)bytes;
#endif
}

/* Start faulting in the whole pages of [data, data + bytes) (nothing for small arrays). */
static inline void prefault_start(Prefault *job, void *data, size_t bytes)
{
    const uintptr_t page = 4096;
    uintptr_t first = ((uintptr_t)data + page - 1) & ~(page - 1), end = ((uintptr_t)data + bytes) & ~(page - 1);
    job->running = 0;
    if (end < first + PREFAULT_MIN_BYTES) {
        return;
    }
    job->start = (char *)first;
    job->length = end - first;
    job->running = pthread_create(&job->thread, NULL, prefault_run, job) == 0;
}

static inline void prefault_join(Prefault *job)
{
    if (job->running) {
        pthread_join(job->thread, NULL);
        job->running = 0;
    }
}

/* Kernels that split an image into bands of rows, one thread each, do so from this many
 * pixels (below it, starting the threads costs more than they save), into at most MAX_BANDS. */
#define BAND_MIN_PIXELS ((int64_t)1 << 21)
#define MAX_BANDS 4

/* CPUs this process may use, as ursim_core.cpus.usable_cpus: URSIM_THREADS when it is a positive
 * integer (a process pool gives each worker its share), else the CPUs it may run on (a container
 * or taskset may allow fewer than the machine has). */
static inline int64_t usable_cpus(void)
{
    const char *told = getenv("URSIM_THREADS");
    if (told != NULL) {
        while (*told == ' ' || *told == '\t')
            told++;
        char *end = NULL;
        long value = strtol(told, &end, 10);
        while (end != NULL && (*end == ' ' || *end == '\t' || *end == '\n'))
            end++;
        if (end != told && end != NULL && *end == '\0' && value > 0 && *told >= '0' && *told <= '9')
            return (int64_t)value;
    }
#ifdef CPU_COUNT
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof(set), &set) == 0) {
        int count = CPU_COUNT(&set);
        return count > 0 ? count : 1;
    }
#endif
    return 1;
}

/* How many parts, one thread each, a pass over ``pixels`` pixels is split into: one per usable
 * CPU from BAND_MIN_PIXELS on, at most MAX_BANDS and ``most`` (e.g. the rows), at least one. */
static inline int64_t parts_for(int64_t pixels, int64_t most)
{
    int64_t n = pixels >= BAND_MIN_PIXELS ? usable_cpus() : 1;
    n = n < MAX_BANDS ? n : MAX_BANDS;
    n = n < most ? n : most;
    return n > 0 ? n : 1;
}

/* ``work(item)`` for each of the ``n`` items of ``size`` bytes at ``items``: the first on this
 * thread, every other on a thread of its own (or on this one afterwards, when a thread cannot
 * start, or no memory is left to start them). Returns when all are done. */
static inline void run_parts(void *items, int64_t n, size_t size, void *(*work)(void *))
{
    char *item = items;
    pthread_t few_threads[MAX_BANDS];
    int few_running[MAX_BANDS] = {0};
    pthread_t *threads = n <= MAX_BANDS ? few_threads : malloc((size_t)n * sizeof(pthread_t));
    int *running = n <= MAX_BANDS ? few_running : calloc((size_t)n, sizeof(int));
    if (threads == NULL || running == NULL) {
        for (int64_t k = 0; k < n; k++) {
            work(item + k * size);
        }
    } else {
        for (int64_t k = 1; k < n; k++) {
            running[k] = pthread_create(&threads[k], NULL, work, item + k * size) == 0;
        }
        if (n > 0) {
            work(item);
        }
        for (int64_t k = 1; k < n; k++) {
            if (running[k]) {
                pthread_join(threads[k], NULL);
            } else {
                work(item + k * size);
            }
        }
    }
    if (threads != few_threads) {
        free(threads);
        free(running);
    }
}

/* A part of a relabelling, for a thread: labels[i] = lookup[labels[i]] for first <= i < end,
 * except that with ``keep_zero`` 0 stays 0 whatever lookup[0] is (a band's own lookup, which
 * is a window of a larger one). */
typedef struct {
    int32_t *labels;
    int64_t first, end;
    const int32_t *lookup;
    int keep_zero;
} RelabelPart;

static void *relabel_part(void *arg)
{
    RelabelPart *part = arg;
    int32_t *labels = part->labels;
    const int32_t *lookup = part->lookup;
    if (part->keep_zero) {
        for (int64_t i = part->first; i < part->end; i++) {
            int32_t label = labels[i];
            labels[i] = label != 0 ? lookup[label] : 0;
        }
    } else {
        for (int64_t i = part->first; i < part->end; i++) {
            labels[i] = lookup[labels[i]];
        }
    }
    return NULL;
}

/* flat_zones.relabel's loop, ``labels[i] = lookup[labels[i]]`` for i < n (also used by contacts
 * and fusion): in parts on threads (parts_for; at 8000 x 8000 px a pass reads and writes 256 MB
 * and is bound by one core's memory traffic). */
static inline void relabel_in_place(int32_t *labels, int64_t n, const int32_t *lookup)
{
    int64_t n_parts = parts_for(n, n);
    RelabelPart parts[MAX_BANDS];
    for (int64_t k = 0; k < n_parts; k++) {
        parts[k] = (RelabelPart){labels, n * k / n_parts, n * (k + 1) / n_parts, lookup, 0};
    }
    run_parts(parts, n_parts, sizeof(RelabelPart), relabel_part);
}

#endif
