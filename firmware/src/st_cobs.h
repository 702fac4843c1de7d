/* Consistent Overhead Byte Stuffing (Cheshire & Baker 1999). The encoded block contains no
 * 0x00 byte; the wire frame is the encoded block followed by one 0x00 delimiter. */
#ifndef ST_COBS_H
#define ST_COBS_H
#include <stdint.h>
#include <stddef.h>

/* Worst-case encoded length of n raw bytes (without the delimiter). */
#define ST_COBS_MAX(n) ((n) + ((n) / 254u) + 1u)

/* Encode n bytes of src into dst (capacity ST_COBS_MAX(n)); returns the encoded length. */
size_t st_cobs_encode(const uint8_t *src, size_t n, uint8_t *dst);

/* Decode n encoded bytes (no delimiter) into dst (capacity cap). Returns the decoded length,
 * -1 when the block is malformed (a zero byte, a code running past the end), or -2 when the
 * decoded data would not fit in cap bytes. */
int st_cobs_decode(const uint8_t *src, size_t n, uint8_t *dst, size_t cap);

#endif
