#include "st_cobs.h"

size_t st_cobs_encode(const uint8_t *src, size_t n, uint8_t *dst)
{
    size_t out = 1, code_at = 0, i;
    uint8_t code = 1;
    for (i = 0; i < n; i++) {
        if (src[i] == 0) {
            dst[code_at] = code;
            code_at = out++;
            code = 1;
        } else {
            dst[out++] = src[i];
            code++;
            if (code == 0xFF) {
                dst[code_at] = code;
                code = 1;
                if (i + 1 == n) {
                    return out; /* a full block ends the data: no trailing code */
                }
                code_at = out++;
            }
        }
    }
    dst[code_at] = code;
    return out;
}

int st_cobs_decode(const uint8_t *src, size_t n, uint8_t *dst, size_t cap)
{
    size_t in = 0, out = 0;
    while (in < n) {
        uint8_t code = src[in++];
        uint8_t k;
        if (code == 0) {
            return -1;
        }
        for (k = 1; k < code; k++) {
            if (in >= n || src[in] == 0) {
                return -1;
            }
            if (out >= cap) {
                return -2;
            }
            dst[out++] = src[in++];
        }
        if (code != 0xFF && in < n) {
            if (out >= cap) {
                return -2;
            }
            dst[out++] = 0;
        }
    }
    return (int)out;
}
