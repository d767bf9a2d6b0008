/* Alignments of long neighbour orders, bit-parallel (module ``_matching_kernels``, see module.c).
 *
 * A port of ursim_core/matching/edit_kernel.py's pack_same and packed_codes, which stay the
 * reference: a generated 8000 px building has one corridor bordering about 4250 rooms, and every
 * hypothesis of the planar matcher aligns an arc of its neighbour order against one of the other
 * map's corridor (about 18 million cells; 50-60 of them per value of m). A table of them is
 * 72 MB of int32 and 18 million cells to fill; here the "same" bits of the two whole orders are
 * packed once per match (PackedOrders, 4.6 MB for two 4250-room corridors) and an arc pair is
 * aligned by Myers' recurrence in Hyyro's block form, 64 rows per word. The +-1 differences of
 * every column are kept, which gives back every table value the backtrace reads, so the backtrace
 * and its ties are those of edit_distance.levenshtein (planar.c's table gives the same pairs).
 *
 * Per match (bit_reset empties them): the packed orders by (sketch vertex, metric vertex,
 * reflected), as planar.py's ``packed`` dict; the aligned pairs of every arc pair by its
 * positions, as arcs.py's ``arc_cache``. Both are bounded (PACK_WORDS, ARENA_INTS): past the bound
 * they are emptied and built again as needed, which changes the time, never the pairs.
 */
#include "kernels.h"

#include <stdlib.h>
#include <string.h>

/* Words of packed orders kept at once (256 MB), and int32 of remembered pairs (128 MB). */
#define PACK_WORDS ((size_t)1 << 25)
#define ARENA_INTS ((size_t)1 << 25)

static void free_packs(Planar *p)
{
    for (int32_t k = 0; k < p->n_packs; k++) {
        free(p->packs[k].bits);
    }
    p->n_packs = 0;
    p->pack_words = 0;
}

static void clear_arcs(Planar *p)
{
    if (p->n_arcs > 0) {
        memset(p->arcs, 0, sizeof(ArcEntry) * p->arcs_capacity);
    }
    p->n_arcs = 0;
    p->arena_used = 0;
}

void bit_reset(Planar *p)
{
    free_packs(p);
    clear_arcs(p);
}

void bit_free(Planar *p)
{
    free_packs(p);
    free(p->packs);
    free(p->deltas);
    free(p->arcs);
    free(p->arena);
    p->packs = NULL;
    p->deltas = NULL;
    p->arcs = NULL;
    p->arena = NULL;
    p->packs_capacity = 0;
    p->deltas_words = p->arcs_capacity = p->n_arcs = p->arena_capacity = p->arena_used = 0;
}

/* Position ``k`` of a sketch vertex's order (reversed when ``reflected``). */
static inline int32_t first_at(const int32_t *order, int32_t size, int reflected, int32_t k)
{
    return reflected ? order[size - 1 - k] : order[k];
}

/* pack_same: the orders of (v, w), the first reversed when ``reflected``; NULL when out of memory. */
static const PackedOrders *packed_orders(Planar *p, int32_t v, int32_t w, int reflected)
{
    for (int32_t k = 0; k < p->n_packs; k++) {
        const PackedOrders *o = &p->packs[k];
        if (o->v == v && o->w == w && o->reflected == reflected) {
            return o;
        }
    }
    const Graphs *g = &p->g;
    const int32_t *order1 = g->nb1 + g->off1[v], *order2 = g->nb2 + g->off2[w];
    int32_t size1 = g->off1[v + 1] - g->off1[v], size2 = g->off2[w + 1] - g->off2[w];
    int32_t words = (2 * size1 + 63) / 64 + 1;
    size_t need = (size_t)size2 * (size_t)words;
    if (p->pack_words + need > PACK_WORDS) {
        free_packs(p);
    }
    if (p->n_packs == p->packs_capacity) {
        int32_t capacity = p->packs_capacity ? 2 * p->packs_capacity : 8;
        PackedOrders *grown = realloc(p->packs, sizeof(PackedOrders) * (size_t)capacity);
        if (grown == NULL) {
            p->failed = 1;
            return NULL;
        }
        p->packs = grown;
        p->packs_capacity = capacity;
    }
    uint64_t *bits = calloc(need, sizeof(uint64_t));
    if (bits == NULL) {
        p->failed = 1;
        return NULL;
    }
    /* 64 rows of the first order at a time, into one word per element of the second order: eight
     * rows a pass, each read where the second order points into it (eight rows of ``same`` stay
     * in cache), and each word updated once per eight bits. */
    uint64_t *gathered = malloc(sizeof(uint64_t) * ((size_t)size2 + 1));
    if (gathered == NULL) {
        free(bits);
        p->failed = 1;
        return NULL;
    }
    for (int32_t start = 0; start < size1; start += 64) {
        int32_t stop = start + 64 < size1 ? start + 64 : size1;
        memset(gathered, 0, sizeof(uint64_t) * (size_t)size2);
        for (int32_t k = start; k < stop; k += 8) {
            const uint8_t *row[8];
            for (int r = 0; r < 8; r++) { /* past the order's end, its last row (masked out below) */
                int32_t position = k + r < stop ? k + r : stop - 1;
                row[r] = g->same + (int64_t)first_at(order1, size1, reflected, position) * g->n2;
            }
            uint64_t mask = stop - k >= 8 ? 0xFF : ((uint64_t)1 << (stop - k)) - 1;
            int shift = k - start;
            for (int32_t q = 0; q < size2; q++) {
                int32_t column = order2[q];
                uint64_t eight = (uint64_t)(row[0][column] != 0) | (uint64_t)(row[1][column] != 0) << 1
                                 | (uint64_t)(row[2][column] != 0) << 2 | (uint64_t)(row[3][column] != 0) << 3
                                 | (uint64_t)(row[4][column] != 0) << 4 | (uint64_t)(row[5][column] != 0) << 5
                                 | (uint64_t)(row[6][column] != 0) << 6 | (uint64_t)(row[7][column] != 0) << 7;
                gathered[q] |= (eight & mask) << shift;
            }
        }
        for (int32_t q = 0; q < size2; q++) {
            bits[(size_t)q * words + (size_t)(start >> 6)] = gathered[q];
        }
    }
    free(gathered);
    /* The first order twice over, so that any cyclic range of it is one straight run of bits:
     * bits 0 .. size1 - 1 again from bit size1 on. Written from the last word down, so that the
     * original words are read before the copy reaches them. */
    int shift = size1 & 63;
    int32_t base = size1 >> 6, used = (size1 + 63) / 64;
    for (int32_t q = 0; q < size2; q++) {
        uint64_t *row = bits + (size_t)q * words;
        for (int32_t word = used - 1; word >= 0; word--) {
            uint64_t value = row[word];
            row[base + word] |= value << shift;
            if (shift != 0) {
                row[base + word + 1] |= value >> (64 - shift);
            }
        }
    }
    PackedOrders *o = &p->packs[p->n_packs++];
    *o = (PackedOrders){v, w, reflected, size1, size2, words, bits};
    p->pack_words += need;
    return o;
}

/* The 64 bits of ``row`` from bit ``offset`` on. */
static inline uint64_t window(const uint64_t *row, int64_t offset)
{
    int64_t word = offset >> 6;
    int shift = (int)(offset & 63);
    uint64_t value = row[word] >> shift;
    if (shift != 0) {
        value |= row[word + 1] << (64 - shift);
    }
    return value;
}

/* The distance of positions start1 .. start1 + rows - 1 (cyclic) of the packed first order against
 * start2 .. start2 + cols - 1 of the second (rows, cols >= 1). With ``keep``, every column's
 * differences are left in p->deltas (column j, block b: +v, -v, +h, -h), for the backtrace.
 * Returns -1 when out of memory. */
static int64_t packed_distance(Planar *p, const PackedOrders *o, int32_t start1, int32_t rows, int32_t start2,
                               int32_t cols, int keep)
{
    int32_t blocks = (rows + 63) / 64;
    size_t need = 2 * (size_t)blocks + (keep ? 4 * (size_t)blocks * (size_t)cols : 0);
    if (need > p->deltas_words) {
        free(p->deltas);
        p->deltas = malloc(sizeof(uint64_t) * need);
        p->deltas_words = p->deltas == NULL ? 0 : need;
        if (p->deltas == NULL) {
            p->failed = 1;
            return -1;
        }
    }
    uint64_t *pv = p->deltas, *mv = pv + blocks, *kept = mv + blocks;
    for (int32_t b = 0; b < blocks; b++) {
        pv[b] = ~(uint64_t)0; /* column 0: D[i][0] = i, every step +1 */
        mv[b] = 0;
    }
    for (int32_t j = 0; j < cols; j++) {
        int32_t q = start2 + j;
        q = q >= o->size2 ? q - o->size2 : q;
        const uint64_t *row = o->bits + (size_t)q * o->words;
        /* The horizontal difference carried into each block, as two bits (+1, -1; never both).
         * Row 0: D[0][j] = j, every step +1. */
        uint64_t carry_plus = 1, carry_minus = 0;
        uint64_t *column = kept + 4 * (size_t)blocks * (size_t)j;
        for (int32_t b = 0; b < blocks; b++) {
            uint64_t eq = window(row, (int64_t)start1 + 64 * (int64_t)b);
            uint64_t pb = pv[b], mb = mv[b];
            uint64_t xv = eq | mb;
            eq |= carry_minus;
            uint64_t xh = (((eq & pb) + pb) ^ pb) | eq;
            uint64_t ph = mb | ~(xh | pb);
            uint64_t mh = pb & xh;
            uint64_t out_plus = ph >> 63, out_minus = mh >> 63;
            if (keep) {
                column[4 * b + 2] = ph;
                column[4 * b + 3] = mh;
            }
            ph = (ph << 1) | carry_plus;
            mh = (mh << 1) | carry_minus;
            pb = mh | ~(xv | ph);
            mb = ph & xv;
            pv[b] = pb;
            mv[b] = mb;
            if (keep) {
                column[4 * b] = pb;
                column[4 * b + 1] = mb;
            }
            carry_plus = out_plus;
            carry_minus = out_minus;
        }
    }
    /* D[rows][cols] from the last column's vertical differences (D[0][cols] = cols). */
    int64_t value = cols;
    for (int32_t b = 0; b < blocks; b++) {
        int32_t bits_here = rows - 64 * b;
        uint64_t mask = bits_here >= 64 ? ~(uint64_t)0 : (((uint64_t)1 << bits_here) - 1);
        value += (int64_t)__builtin_popcountll(pv[b] & mask) - (int64_t)__builtin_popcountll(mv[b] & mask);
    }
    return value;
}

/* Bit ``i`` (0-based row) of the +1 and -1 words ``k`` and ``k + 1`` of column ``column``, as -1, 0 or +1. */
static inline int64_t delta(const uint64_t *column, int32_t i, int k)
{
    const uint64_t *words = column + 4 * (size_t)(i >> 6);
    int bit = i & 63;
    return (int64_t)((words[k] >> bit) & 1) - (int64_t)((words[k + 1] >> bit) & 1);
}

/* aligned_index_pairs of the two cyclic ranges (packed_codes' backtrace, its diagonal steps),
 * written to ``out`` first elements first; returns their number (-1: out of memory). */
static int32_t packed_pairs(Planar *p, const PackedOrders *o, int32_t start1, int32_t rows, int32_t start2,
                            int32_t cols, int32_t *out)
{
    int64_t value = packed_distance(p, o, start1, rows, start2, cols, 1);
    if (value < 0) {
        return -1;
    }
    const Graphs *g = &p->g;
    const int32_t *order1 = g->nb1 + g->off1[o->v], *order2 = g->nb2 + g->off2[o->w];
    int32_t blocks = (rows + 63) / 64, count = 0;
    const uint64_t *kept = p->deltas + 2 * (size_t)blocks;
    int32_t i = rows, j = cols;
    while (i > 0 && j > 0) {
        const uint64_t *column = kept + 4 * (size_t)blocks * (size_t)(j - 1);
        int64_t up = value - delta(column, i - 1, 0), left = value - delta(column, i - 1, 2);
        int64_t diagonal = i == 1 ? j - 1 : up - delta(column, i - 2, 2);
        if (diagonal <= up && diagonal <= left) {
            value = diagonal;
            i--;
            j--;
            int32_t k1 = start1 + i, k2 = start2 + j;
            out[2 * count] = first_at(order1, o->size1, o->reflected, k1 >= o->size1 ? k1 - o->size1 : k1);
            out[2 * count + 1] = order2[k2 >= o->size2 ? k2 - o->size2 : k2];
            count++;
        } else if (left <= up) {
            value = left;
            j--;
        } else {
            value = up;
            i--;
        }
    }
    reverse_pairs(out, count); /* first elements first */
    return count;
}

/* planar.c's seed_pairs for orders too long for its table: the rotation (and reflection) of the
 * sketch vertex's order with the lowest distance (ties: the smallest offset, unreflected first;
 * 'first' keeps offset 0) and the pairs it aligns. */
int32_t bit_seed_pairs(Planar *p, int32_t v, int32_t w, int rotation_min, int reflections, int *reflected,
                       int32_t *out)
{
    const Graphs *g = &p->g;
    int32_t rows = g->off1[v + 1] - g->off1[v], cols = g->off2[w + 1] - g->off2[w];
    const PackedOrders *o;
    int64_t best = -1;
    int32_t best_offset = 0;
    int best_reflected = 0;
    if (rotation_min && rows > 1) {
        for (int flip = 0; flip <= (reflections ? 1 : 0) && best != 0; flip++) {
            if ((o = packed_orders(p, v, w, flip)) == NULL) {
                return 0;
            }
            for (int32_t offset = 0; offset < rows; offset++) {
                int64_t distance = packed_distance(p, o, offset, rows, 0, cols, 0);
                if (distance < 0) {
                    return 0;
                }
                if (best < 0 || distance < best) {
                    best = distance;
                    best_offset = offset;
                    best_reflected = flip;
                    if (distance == 0) {
                        break;
                    }
                }
            }
        }
    }
    *reflected = best_reflected;
    if ((o = packed_orders(p, v, w, best_reflected)) == NULL) {
        return 0;
    }
    int32_t count = packed_pairs(p, o, best_offset, rows, 0, cols, out);
    return count < 0 ? 0 : count;
}

static inline uint64_t arc_hash(const int32_t *key)
{
    uint64_t h = 0x9E3779B97F4A7C15ULL;
    for (int k = 0; k < 7; k++) {
        h = (h ^ (uint32_t)key[k]) * 0xBF58476D1CE4E5B9ULL;
        h ^= h >> 29;
    }
    return h;
}

/* The slot of ``key`` in the open-addressed table (its own, or the empty one where it goes). */
static ArcEntry *arc_slot(ArcEntry *arcs, size_t capacity, const int32_t *key)
{
    size_t k = arc_hash(key) & (capacity - 1);
    while (arcs[k].key[4] != 0 && memcmp(arcs[k].key, key, sizeof(arcs[k].key)) != 0) {
        k = (k + 1) & (capacity - 1);
    }
    return &arcs[k];
}

static int grow_arcs(Planar *p)
{
    size_t capacity = p->arcs_capacity ? 2 * p->arcs_capacity : 1024;
    ArcEntry *arcs = calloc(capacity, sizeof(ArcEntry));
    if (arcs == NULL) {
        return -1;
    }
    for (size_t k = 0; k < p->arcs_capacity; k++) {
        if (p->arcs[k].key[4] != 0) {
            *arc_slot(arcs, capacity, p->arcs[k].key) = p->arcs[k];
        }
    }
    free(p->arcs);
    p->arcs = arcs;
    p->arcs_capacity = capacity;
    return 0;
}

/* arcs.py's _expand_packed for one arc pair: the pairs aligned between positions start1 ..
 * start1 + rows - 1 of the sketch vertex's order (reversed when ``reflected``) and start2 ..
 * start2 + cols - 1 of the metric vertex's (cyclic; rows, cols >= 1), aligned once per match.
 * The pointer is valid until the next call; NULL (and p->failed) when out of memory. */
const int32_t *bit_arc_pairs(Planar *p, int32_t v, int32_t w, int reflected, int32_t start1, int32_t rows,
                             int32_t start2, int32_t cols, int32_t *count)
{
    int32_t key[7] = {v, w, reflected, start1, rows, start2, cols};
    if (2 * (p->n_arcs + 1) > p->arcs_capacity && grow_arcs(p) < 0) {
        p->failed = 1;
        return NULL;
    }
    ArcEntry *entry = arc_slot(p->arcs, p->arcs_capacity, key);
    if (entry->key[4] != 0) {
        *count = entry->count;
        return p->arena + entry->offset;
    }
    size_t most = 2 * (size_t)(rows < cols ? rows : cols);
    if (p->arena_used + most > ARENA_INTS && p->arena_used > 0) {
        clear_arcs(p);
        entry = arc_slot(p->arcs, p->arcs_capacity, key);
    }
    if (p->arena_used + most > p->arena_capacity) {
        size_t capacity = p->arena_capacity ? p->arena_capacity : 4096;
        while (capacity < p->arena_used + most) {
            capacity *= 2;
        }
        int32_t *arena = realloc(p->arena, sizeof(int32_t) * capacity);
        if (arena == NULL) {
            p->failed = 1;
            return NULL;
        }
        p->arena = arena;
        p->arena_capacity = capacity;
    }
    const PackedOrders *o = packed_orders(p, v, w, reflected);
    int32_t found = o == NULL ? -1 : packed_pairs(p, o, start1, rows, start2, cols, p->arena + p->arena_used);
    if (found < 0) {
        return NULL;
    }
    memcpy(entry->key, key, sizeof(key));
    entry->count = found;
    entry->offset = p->arena_used;
    p->arena_used += 2 * (size_t)found;
    p->n_arcs++;
    *count = found;
    return p->arena + entry->offset;
}
