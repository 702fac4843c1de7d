#include <string.h>
#include "st_link.h"
#include "st_crc16.h"

size_t st_frame_encode(uint8_t type, uint16_t seq, const uint8_t *payload, uint8_t len,
                       uint8_t *wire)
{
    uint8_t body[ST_MAX_BODY];
    size_t n;
    uint16_t crc;
    if (len > ST_MAX_PAYLOAD) {
        len = ST_MAX_PAYLOAD;
    }
    body[0] = type;
    st_put_u16(body + 1, seq);
    if (len) {
        memcpy(body + ST_HEADER_LEN, payload, len);
    }
    crc = st_crc16(body, (size_t)ST_HEADER_LEN + len);
    st_put_u16(body + ST_HEADER_LEN + len, crc);
    n = st_cobs_encode(body, (size_t)ST_HEADER_LEN + len + ST_CRC_LEN, wire);
    wire[n++] = 0;
    return n;
}

int st_frame_decode(const uint8_t *block, size_t n, st_frame_t *out)
{
    uint8_t body[ST_MAX_BODY];
    int len = st_cobs_decode(block, n, body, sizeof body);
    uint16_t crc;
    if (len == -2) {
        return -2; /* longer than any valid frame */
    }
    if (len < 0) {
        return -1;
    }
    if (len < (int)(ST_HEADER_LEN + ST_CRC_LEN)) {
        return -2;
    }
    crc = st_crc16(body, (size_t)len - ST_CRC_LEN);
    if (crc != st_get_u16(body + len - ST_CRC_LEN)) {
        return -3;
    }
    out->type = body[0];
    out->seq = st_get_u16(body + 1);
    out->len = (uint8_t)(len - ST_HEADER_LEN - ST_CRC_LEN);
    memcpy(out->payload, body + ST_HEADER_LEN, out->len);
    return 0;
}

void st_rx_init(st_rx_t *rx)
{
    memset(rx, 0, sizeof *rx);
}

int st_rx_feed(st_rx_t *rx, uint8_t byte, st_frame_t *out)
{
    int ok = 0;
    if (byte != 0) {
        if (rx->n < sizeof rx->buf) {
            rx->buf[rx->n++] = byte;
        } else {
            rx->overflow = 1;
        }
        return 0;
    }
    if (rx->n == 0) {
        return 0; /* empty frame: a spare delimiter */
    }
    if (!rx->overflow && st_frame_decode(rx->buf, rx->n, out) == 0) {
        ok = 1;
    } else {
        rx->bad++;
    }
    rx->n = 0;
    rx->overflow = 0;
    return ok;
}

void st_ring_init(st_ring_t *r)
{
    memset(r, 0, sizeof *r);
}

int st_ring_has_room(const st_ring_t *r)
{
    return (uint16_t)(r->next_seq - r->acked) < ST_RING_FRAMES;
}

int st_ring_push(st_ring_t *r, uint8_t type, const uint8_t *payload, uint8_t len)
{
    uint8_t slot = (uint8_t)(r->next_seq & (ST_RING_FRAMES - 1u));
    uint8_t *b = r->body[slot];
    if (!st_ring_has_room(r)) {
        return -1;
    }
    if (len > ST_MAX_PAYLOAD) {
        len = ST_MAX_PAYLOAD;
    }
    b[0] = type;
    st_put_u16(b + 1, r->next_seq);
    if (len) {
        memcpy(b + ST_HEADER_LEN, payload, len);
    }
    r->blen[slot] = len;
    r->next_seq++;
    return 0;
}

void st_ring_ack(st_ring_t *r, uint16_t seq)
{
    /* valid when acked <= seq <= next_seq (modulo 2^16) */
    if ((uint16_t)(seq - r->acked) <= (uint16_t)(r->next_seq - r->acked)) {
        r->acked = seq;
        if ((uint16_t)(r->tx_seq - r->acked) > (uint16_t)(r->next_seq - r->acked)) {
            r->tx_seq = r->acked;
        }
    }
}

int st_ring_nak(st_ring_t *r, uint16_t seq)
{
    uint16_t span = (uint16_t)(r->next_seq - r->acked);
    uint16_t off = (uint16_t)(seq - r->acked);
    if (off > span) {
        /* before the oldest kept frame (lost for good) or beyond the newest (never sent) */
        return (uint16_t)(r->next_seq - seq) < 0x8000u ? ST_ERR_LOST : ST_ERR_NAK_RANGE;
    }
    r->acked = seq;
    r->tx_seq = seq;
    return 0;
}

size_t st_ring_next_wire(st_ring_t *r, uint8_t *wire)
{
    uint8_t slot;
    if (r->tx_seq == r->next_seq) {
        return 0;
    }
    slot = (uint8_t)(r->tx_seq & (ST_RING_FRAMES - 1u));
    r->tx_seq++;
    return st_frame_encode(r->body[slot][0], st_get_u16(r->body[slot] + 1),
                           r->body[slot] + ST_HEADER_LEN, r->blen[slot], wire);
}
