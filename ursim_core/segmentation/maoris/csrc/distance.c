/* MAORIS step 1's exact Euclidean distance transform in C (port of ../kernels/distance.py, whose
 * docstring gives the method). Both passes go along rows, on threads: the column distances in
 * parts of the columns (each part sweeping the rows down, then up), the rows' lower envelopes in
 * bands of rows. */
#include "kernels.h"

#include <math.h>

/* OpenCV's distance for an image without any obstacle pixel (2**64 as a float). */
#define NO_OBSTACLE 18446744073709551616.0f
#define MAX_SIDE ((int64_t)1 << 20)

typedef struct {
    const Array *free_mask;
    int32_t *column; /* the output's memory read as int32: -1 = no obstacle that way */
    int64_t rows, cols, first, end; /* columns first .. end - 1 (pass 1) or rows (pass 2) */
    int failed;
} DistancePart;

static inline int is_free(const Array *free_mask, int64_t row, int64_t col)
{
    const uint8_t *data = free_mask->data;
    return data[row * free_mask->row_stride + col * free_mask->col_stride] != 0;
}

/* Pass 1 on columns first .. end - 1: the distance along the column to the nearest obstacle. */
static void *column_part(void *arg)
{
    DistancePart *p = arg;
    int64_t cols = p->cols;
    for (int64_t col = p->first; col < p->end; col++) {
        p->column[col] = is_free(p->free_mask, 0, col) ? -1 : 0;
    }
    for (int64_t row = 1; row < p->rows; row++) {
        const int32_t *above = p->column + (row - 1) * cols;
        int32_t *here = p->column + row * cols;
        for (int64_t col = p->first; col < p->end; col++) {
            here[col] = !is_free(p->free_mask, row, col) ? 0 : (above[col] < 0 ? -1 : above[col] + 1);
        }
    }
    for (int64_t row = p->rows - 2; row >= 0; row--) {
        const int32_t *below = p->column + (row + 1) * cols;
        int32_t *here = p->column + row * cols;
        for (int64_t col = p->first; col < p->end; col++) {
            if (below[col] >= 0 && (here[col] < 0 || below[col] + 1 < here[col])) {
                here[col] = below[col] + 1;
            }
        }
    }
    return NULL;
}

/* Pass 2 on rows first .. end - 1: each row's lower envelope of parabolas, read off at every
 * column, over the row's column distances (copied out first: the floats are written over them). */
static void *row_part(void *arg)
{
    DistancePart *p = arg;
    int64_t cols = p->cols;
    int64_t *buffer = malloc((size_t)(4 * cols + 2) * sizeof(int64_t));
    if (buffer == NULL) {
        p->failed = 1;
        return NULL;
    }
    int64_t *squared = buffer, *vertex = buffer + cols;
    int64_t *start_num = buffer + 2 * cols, *start_den = buffer + 3 * cols + 1;
    for (int64_t row = p->first; row < p->end; row++) {
        const int32_t *column = p->column + row * cols;
        float *out = (float *)(p->column + row * cols);
        for (int64_t col = 0; col < cols; col++) {
            int64_t g = column[col];
            squared[col] = g >= 0 ? g * g : -1;
        }
        int64_t last = -1;
        for (int64_t q = 0; q < cols; q++) {
            if (squared[q] < 0) {
                continue;
            }
            int64_t num = 0, den = 1;
            while (last >= 0) {
                int64_t v = vertex[last];
                num = (squared[q] + q * q) - (squared[v] + v * v);
                den = 2 * (q - v);
                if (last > 0 && num * start_den[last] <= start_num[last] * den) {
                    last--;
                } else {
                    break;
                }
            }
            last++;
            vertex[last] = q;
            start_num[last] = num;
            start_den[last] = den;
        }
        if (last < 0) {
            for (int64_t col = 0; col < cols; col++) {
                out[col] = NO_OBSTACLE;
            }
            continue;
        }
        int64_t k = 0;
        for (int64_t x = 0; x < cols; x++) {
            while (k < last && start_num[k + 1] < x * start_den[k + 1]) {
                k++;
            }
            int64_t offset = x - vertex[k];
            out[x] = sqrtf((float)(squared[vertex[k]] + offset * offset));
        }
    }
    free(buffer);
    return NULL;
}

KERNEL(distance_transform)
{
    Array free_mask, out;
    if (check_nargs("distance_transform", nargs, 2) || array_arg(args[0], NPY_UINT8, 2, 1, "free", &free_mask)
        || array_arg(args[1], NPY_FLOAT32, 2, 0, "out", &out)) {
        return NULL;
    }
    if (check_same_shape("distance_transform", "free", &free_mask, "out", &out)) {
        return NULL;
    }
    int64_t rows = out.rows, cols = out.cols;
    if (rows >= MAX_SIDE || cols >= MAX_SIDE) {
        PyErr_SetString(PyExc_ValueError, "distance_transform: a side of 2**20 px or more");
        return NULL;
    }
    if (rows == 0 || cols == 0) {
        Py_RETURN_NONE;
    }
    int failed = 0;
    Py_BEGIN_ALLOW_THREADS
    DistancePart parts[MAX_BANDS];
    int64_t n_parts = parts_for(rows * cols, cols);
    for (int64_t k = 0; k < n_parts; k++) {
        parts[k] = (DistancePart){&free_mask, out.data, rows, cols, cols * k / n_parts, cols * (k + 1) / n_parts, 0};
    }
    run_parts(parts, n_parts, sizeof(DistancePart), column_part);
    n_parts = parts_for(rows * cols, rows);
    for (int64_t k = 0; k < n_parts; k++) {
        parts[k] = (DistancePart){&free_mask, out.data, rows, cols, rows * k / n_parts, rows * (k + 1) / n_parts, 0};
    }
    run_parts(parts, n_parts, sizeof(DistancePart), row_part);
    for (int64_t k = 0; k < n_parts; k++) {
        failed |= parts[k].failed;
    }
    Py_END_ALLOW_THREADS
    if (failed) {
        return PyErr_NoMemory();
    }
    Py_RETURN_NONE;
}
