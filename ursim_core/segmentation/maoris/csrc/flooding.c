/* Marker flooding of the clearance watershed in C (port of ../kernels/flooding.py, whose
 * docstrings explain the method: scikit-image's priority flood with one uint64 an entry,
 * ``level | age | pixel``, in a binary heap while tied markers of two labels remain, then a
 * FIFO per level; and the levels of a clearance through the squares of its values).
 *
 * The heap must make scikit-image's moves exactly (the pop order of equal markers depends on
 * where the whole history left them, and it changes labels): sift_up and sift_down are the
 * numba helpers line for line. */
#include "kernels.h"

#include <math.h>

/* The label of the pixels outside the mask while flooding: one test of a neighbour, since a
 * free unlabelled pixel is 0. Undone (restore_outside) on every return. */
#define OUTSIDE INT32_MIN

enum { FLOODED = 0, TOO_WIDE = -1, NO_MEMORY = -2 };

/* skimage.morphology's neighbours (row, col steps), by distance then raster offset
 * (connectivity 1: the first 4). */
static const int64_t STEPS[8][2] = {{-1, 0}, {0, -1}, {0, 1}, {1, 0}, {-1, -1}, {-1, 1}, {1, -1}, {1, 1}};

static inline int64_t bit_length(int64_t value) { return value > 0 ? 64 - __builtin_clzll((uint64_t)value) : 0; }

/* The level shift is 64 only when every level is 0 (and the image has over 2^31 pixels): a
 * shift by 64 is undefined in C (and in numba's LLVM), so say what it means, 0. */
static inline uint64_t shift_left(uint64_t value, uint64_t shift) { return shift < 64 ? value << shift : 0; }
static inline uint64_t shift_right(uint64_t value, uint64_t shift) { return shift < 64 ? value >> shift : 0; }

static void restore_outside(int32_t *labels, int64_t n)
{
    for (int64_t i = 0; i < n; i++) {
        labels[i] = labels[i] == OUTSIDE ? 0 : labels[i];
    }
}

/* flooding._sift_up: put ``entry`` at ``slot`` and move it up past strictly larger parents. */
static inline void sift_up(uint64_t *heap, int64_t slot, uint64_t entry, uint64_t age_shift)
{
    uint64_t key = entry >> age_shift;
    while (slot > 1 && key < (heap[slot >> 1] >> age_shift)) {
        heap[slot] = heap[slot >> 1];
        slot >>= 1;
    }
    heap[slot] = entry;
}

/* flooding._sift_down: refill the root with ``last`` after a pop (down along the smaller
 * children to a leaf, the left one on ties, then back up past those not smaller than ``last``:
 * where scikit-image's sift-down leaves every entry). */
static inline void sift_down(uint64_t *heap, int64_t items, uint64_t last, uint64_t age_shift)
{
    uint64_t key = last >> age_shift;
    int64_t slot = 1;
    for (;;) {
        int64_t child = 2 * slot;
        if (child >= items) {
            if (child == items) {
                heap[slot] = heap[child];
                slot = child;
            }
            break;
        }
        PREFETCH(heap + 8 * slot); /* the great-grandchildren: one cache line */
        uint64_t left = heap[child], right = heap[child + 1];
        child += (int64_t)((right >> age_shift) < (left >> age_shift));
        heap[slot] = heap[child];
        slot = child;
    }
    while (slot > 1 && (heap[slot >> 1] >> age_shift) >= key) {
        heap[slot] = heap[slot >> 1];
        slot >>= 1;
    }
    heap[slot] = last;
}

/* What the two floods share: the images, the neighbours, the layout of an entry and the heap
 * (slots 1..items of capacity). */
typedef struct {
    const uint32_t *levels;
    int32_t *labels;
    int64_t rows, cols;
    int64_t steps, flat_steps[8]; /* flooding._steps: any connectivity but 1 is 8 neighbours */
    uint64_t age_shift, level_shift, pixel_mask;
    uint64_t *heap;
    int64_t items, capacity;
} Flood;

/* The k-th neighbour of ``pixel`` (at row, col) when it lies in the image, free and unlabelled;
 * else -1. */
static inline int64_t unlabelled_neighbour(const Flood *flood, int64_t pixel, int64_t row, int64_t col, int64_t k)
{
    int64_t r = row + STEPS[k][0], c = col + STEPS[k][1];
    if (r < 0 || r >= flood->rows || c < 0 || c >= flood->cols) {
        return -1;
    }
    int64_t neighbour = pixel + flood->flat_steps[k];
    return flood->labels[neighbour] == 0 ? neighbour : -1;
}

/* flooding._last_tie: the highest level whose markers carry two labels or more (-1 if none);
 * -2 when out of memory. */
static int64_t last_tie(const Flood *flood, int64_t n, int64_t top_level)
{
    int32_t *first = calloc((size_t)(top_level + 1), sizeof(int32_t));
    if (first == NULL) {
        return -2;
    }
    int64_t last = -1;
    for (int64_t i = 0; i < n; i++) {
        int32_t label = flood->labels[i];
        if (label == 0 || label == OUTSIDE) {
            continue;
        }
        int64_t level = flood->levels[i];
        if (first[level] == 0) {
            first[level] = label;
        } else if (first[level] != label && level > last) {
            last = level;
        }
    }
    free(first);
    return last;
}

/* flooding._heap_flood: scikit-image's pops while a level of tied markers of two labels
 * remains. Returns FLOODED, or NO_MEMORY (the heap, maybe reallocated, still valid). */
static int heap_flood(Flood *flood, int64_t last_tie_level)
{
    const uint32_t *levels = flood->levels;
    int32_t *labels = flood->labels;
    const int64_t cols = flood->cols, count = flood->steps;
    const uint64_t age_shift = flood->age_shift, level_shift = flood->level_shift, pixel_mask = flood->pixel_mask;
    uint64_t *heap = flood->heap;
    int64_t items = flood->items, capacity = flood->capacity;
    uint64_t age = 1;
    int status = FLOODED;
    while (items > 0) {
        uint64_t popped = heap[1];
        uint64_t level = shift_right(popped, level_shift);
        if ((int64_t)level > last_tie_level) {
            break;
        }
        uint64_t last = heap[items];
        items -= 1;
        if (items > 0) {
            sift_down(heap, items, last, age_shift);
        }
        int64_t pixel = (int64_t)(popped & pixel_mask);
        int64_t row = pixel / cols, col = pixel - row * cols;
        int32_t label = labels[pixel];
        for (int64_t k = 0; k < count; k++) {
            int64_t neighbour = unlabelled_neighbour(flood, pixel, row, col, k);
            if (neighbour < 0) {
                continue;
            }
            age += 1;
            /* Labelled when pushed: no later pop can reach it at a lower cost. */
            labels[neighbour] = label;
            uint64_t raised = levels[neighbour] > level ? (uint64_t)levels[neighbour] : level;
            if (items + 2 > capacity) {
                uint64_t *grown = realloc(heap, (size_t)(2 * capacity) * sizeof(uint64_t));
                if (grown == NULL) {
                    status = NO_MEMORY;
                    goto done;
                }
                heap = grown;
                capacity *= 2;
            }
            items += 1;
            sift_up(heap, items, shift_left(raised, level_shift) | (age << age_shift) | (uint64_t)neighbour, age_shift);
        }
    }
done:
    flood->heap = heap;
    flood->items = items;
    flood->capacity = capacity;
    return status;
}

/* All the remaining entries are distinct (their pixels differ): any ascending sort is np.sort's. */
static int compare_entries(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* flooding._bucket_flood: the rest of the pops in (level, age) order, the heap's entries sorted
 * (with their pixel bits: equal markers, of one label, in raster order), then per level those
 * entries before the pixels pushed since (they are younger). Sorts ``waiting`` in place.
 * Returns FLOODED or NO_MEMORY. */
static int bucket_flood(const Flood *flood, uint64_t *waiting, int64_t items, int64_t n, int64_t top_level)
{
    const uint32_t *levels = flood->levels;
    int32_t *labels = flood->labels;
    const int64_t cols = flood->cols, count = flood->steps;
    const uint64_t level_shift = flood->level_shift, pixel_mask = flood->pixel_mask;
    int32_t *following = malloc((size_t)(n > 0 ? n : 1) * sizeof(int32_t));
    int64_t *head = filled_i64(top_level + 1, -1), *tail = filled_i64(top_level + 1, -1);
    int status = NO_MEMORY;
    if (following == NULL || head == NULL || tail == NULL) {
        goto done;
    }
    qsort(waiting, (size_t)items, sizeof(uint64_t), compare_entries);
    int64_t next_waiting = 0;
    for (int64_t level = 0; level <= top_level; level++) {
        for (;;) {
            int64_t pixel;
            if (next_waiting < items && (int64_t)shift_right(waiting[next_waiting], level_shift) == level) {
                pixel = (int64_t)(waiting[next_waiting] & pixel_mask);
                next_waiting += 1;
            } else if (head[level] >= 0) {
                pixel = head[level];
                head[level] = following[pixel];
            } else {
                break;
            }
            int64_t row = pixel / cols, col = pixel - row * cols;
            int32_t label = labels[pixel];
            for (int64_t k = 0; k < count; k++) {
                int64_t neighbour = unlabelled_neighbour(flood, pixel, row, col, k);
                if (neighbour < 0) {
                    continue;
                }
                labels[neighbour] = label;
                int64_t raised = (int64_t)levels[neighbour] > level ? (int64_t)levels[neighbour] : level;
                following[neighbour] = -1;
                if (head[raised] < 0) {
                    head[raised] = neighbour;
                } else {
                    following[tail[raised]] = (int32_t)neighbour; /* int32, as numba's array */
                }
                tail[raised] = neighbour;
            }
        }
    }
    status = FLOODED;
done:
    free(following);
    free(head);
    free(tail);
    return status;
}

/* flooding.flood_levels on C-contiguous images of n = rows * cols pixels: FLOODED, TOO_WIDE
 * (no flooding: an entry would exceed 64 bits, or a level the pixel count) or NO_MEMORY. */
static int flood_levels(const uint32_t *levels, int32_t *labels, const uint8_t *mask, int64_t rows, int64_t cols,
                        int64_t connectivity)
{
    int64_t n = rows * cols;
    int64_t top_level = 0, markers = 0;
    for (int64_t i = 0; i < n; i++) {
        if (mask[i]) {
            top_level = levels[i] > top_level ? levels[i] : top_level;
            markers += labels[i] != 0;
        } else {
            labels[i] = OUTSIDE;
        }
    }
    int64_t pixel_bits = bit_length(n - 1);
    int64_t age_bits = bit_length(n + 1); /* ages run from 2 to (pushes + 1) <= n + 1 */
    if (pixel_bits + age_bits + bit_length(top_level) > 64 || top_level > n) { /* levels are ranks */
        restore_outside(labels, n);
        return TOO_WIDE;
    }
    int64_t capacity = (markers > 1024 ? markers : 1024) + 2;
    Flood flood = {levels, labels, rows, cols, connectivity == 1 ? 4 : 8, {0}, (uint64_t)pixel_bits,
                   (uint64_t)(pixel_bits + age_bits), ((uint64_t)1 << pixel_bits) - 1,
                   malloc((size_t)capacity * sizeof(uint64_t)), 0, capacity};
    for (int64_t k = 0; k < 8; k++) {
        flood.flat_steps[k] = STEPS[k][0] * cols + STEPS[k][1];
    }
    int status = NO_MEMORY;
    if (flood.heap == NULL) {
        goto done;
    }
    for (int64_t i = 0; i < n; i++) {
        if (labels[i] != 0 && labels[i] != OUTSIDE) {
            flood.items += 1;
            sift_up(flood.heap, flood.items, shift_left(levels[i], flood.level_shift) | (uint64_t)i, flood.age_shift);
        }
    }
    int64_t tie = last_tie(&flood, n, top_level);
    if (tie == -2 || heap_flood(&flood, tie) != FLOODED) {
        goto done;
    }
    status = bucket_flood(&flood, flood.heap + 1, flood.items, n, top_level);
done:
    /* numba leaves the marks on a MemoryError; the labels are then of no use but to be 0 outside. */
    restore_outside(labels, n);
    free(flood.heap);
    return status;
}

KERNEL(flood_levels)
{
    Array levels, labels, mask;
    int64_t connectivity;
    if (check_nargs("flood_levels", nargs, 4) || array_arg(args[0], NPY_UINT32, 2, 0, "levels", &levels)
        || array_arg(args[1], NPY_INT32, 2, 0, "labels", &labels) || array_arg(args[2], NPY_UINT8, 2, 0, "mask", &mask)
        || int_arg(args[3], "connectivity", &connectivity)) {
        return NULL;
    }
    /* numba reads the three with the shape of levels, unchecked */
    if (labels.rows != levels.rows || labels.cols != levels.cols || mask.rows != levels.rows
        || mask.cols != levels.cols) {
        PyErr_SetString(PyExc_ValueError, "flood_levels: levels, labels and mask differ in shape");
        return NULL;
    }
    int status;
    Py_BEGIN_ALLOW_THREADS
    status = flood_levels(levels.data, labels.data, mask.data, levels.rows, levels.cols, connectivity);
    Py_END_ALLOW_THREADS
    if (status == NO_MEMORY) {
        return PyErr_NoMemory();
    }
    return PyLong_FromLong(status);
}

/* flooding.clearance_levels: the malloc'd levels of ``-clearance`` on ``free`` (0 = largest),
 * with *status 0; NULL with *status 1 when the values are not square roots of integers growing
 * with them (the 0 x 0 array), or -1 when out of memory. Comparisons of a float32 with a
 * float64 are in float64, as numba makes them; np.rint is rint (half to even). */
static uint32_t *clearance_levels(const float *clearance, const uint8_t *free_mask, int64_t rows, int64_t cols,
                                  int *status)
{
    int64_t n = rows * cols;
    double top = 0.0;
    for (int64_t i = 0; i < n; i++) {
        if (free_mask[i] && (double)clearance[i] > top) {
            top = clearance[i];
        }
    }
    *status = 1;
    if (!(top * top < (double)n + 2.0)) { /* also NaN; the table stays smaller than the image */
        return NULL;
    }
    int64_t size = (int64_t)rint(top * top) + 1;
    float *values = malloc((size_t)size * sizeof(float));
    uint32_t *rank = calloc((size_t)size, sizeof(uint32_t));
    uint32_t *levels = NULL;
    if (values == NULL || rank == NULL) {
        *status = -1;
        goto done;
    }
    for (int64_t k = 0; k < size; k++) {
        values[k] = -1.0f;
    }
    for (int64_t i = 0; i < n; i++) {
        if (free_mask[i]) {
            float value = clearance[i];
            if (!((double)value >= 0.0)) {
                goto done;
            }
            int64_t k = (int64_t)rint((double)value * (double)value);
            if (values[k] < 0.0) {
                values[k] = value;
            } else if (values[k] != value) {
                goto done;
            }
        }
    }
    int64_t level = -1;
    float previous = INFINITY;
    for (int64_t k = size - 1; k >= 0; k--) {
        if (values[k] < 0.0) {
            continue;
        }
        if (values[k] > previous) {
            goto done;
        }
        if (values[k] < previous) {
            level += 1;
            previous = values[k];
        }
        rank[k] = (uint32_t)level;
    }
    levels = calloc((size_t)(n > 0 ? n : 1), sizeof(uint32_t));
    if (levels == NULL) {
        *status = -1;
        goto done;
    }
    for (int64_t i = 0; i < n; i++) {
        if (free_mask[i]) {
            double value = clearance[i];
            levels[i] = rank[(int64_t)rint(value * value)];
        }
    }
    *status = 0;
done:
    free(values);
    free(rank);
    return levels;
}

KERNEL(clearance_levels)
{
    Array clearance, free_mask;
    if (check_nargs("clearance_levels", nargs, 2) || array_arg(args[0], NPY_FLOAT32, 2, 0, "clearance", &clearance)
        || array_arg(args[1], NPY_UINT8, 2, 0, "free", &free_mask)) {
        return NULL;
    }
    if (check_same_shape("clearance_levels", "clearance", &clearance, "free", &free_mask)) {
        return NULL;
    }
    int status;
    uint32_t *levels;
    Py_BEGIN_ALLOW_THREADS
    levels = clearance_levels(clearance.data, free_mask.data, clearance.rows, clearance.cols, &status);
    Py_END_ALLOW_THREADS
    if (status < 0) {
        return PyErr_NoMemory();
    }
    if (status > 0) {
        return (PyObject *)new_array_2d(0, 0, NPY_UINT32);
    }
    npy_intp dims[2] = {clearance.rows, clearance.cols};
    return array_owning(levels, 2, dims, NPY_UINT32);
}
