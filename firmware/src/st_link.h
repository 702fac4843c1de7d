/* Framing and the device side of the link: frame encode/decode, the receive state machine and
 * the ring buffer of recent transmitted frames (go-back-N retransmission on NAK). */
#ifndef ST_LINK_H
#define ST_LINK_H
#include <stdint.h>
#include <stddef.h>
#include "st_cobs.h"
#include "st_proto.h"

#ifndef ST_RING_FRAMES
#define ST_RING_FRAMES 32u /* power of two; the PIC build uses 4 */
#endif
#define ST_WIRE_MAX (ST_COBS_MAX(ST_MAX_BODY) + 1u)

/* Build the wire form of one frame (COBS + delimiter) into wire[ST_WIRE_MAX]; returns length. */
size_t st_frame_encode(uint8_t type, uint16_t seq, const uint8_t *payload, uint8_t len,
                       uint8_t *wire);

typedef struct {
    uint8_t type;
    uint16_t seq;
    uint8_t len;
    uint8_t payload[ST_MAX_PAYLOAD];
} st_frame_t;

/* Decode one encoded block (the bytes between delimiters, delimiter excluded).
 * Returns 0 on success, -1 malformed COBS, -2 too short/long, -3 bad CRC. */
int st_frame_decode(const uint8_t *block, size_t n, st_frame_t *out);

/* Receive state machine: feed bytes, get whole frames. */
typedef struct {
    uint8_t buf[ST_WIRE_MAX];
    uint8_t n;
    uint8_t overflow;
    uint16_t bad; /* frames dropped: malformed, CRC, overlong */
} st_rx_t;

void st_rx_init(st_rx_t *rx);
/* Returns 1 when `out` holds a new valid frame, 0 otherwise. */
int st_rx_feed(st_rx_t *rx, uint8_t byte, st_frame_t *out);

/* Transmit side: every sequenced frame is kept until acknowledged. */
typedef struct {
    uint8_t body[ST_RING_FRAMES][ST_MAX_BODY];
    uint8_t blen[ST_RING_FRAMES];
    uint16_t next_seq; /* sequence number of the next new frame */
    uint16_t acked;    /* all frames before this one are acknowledged */
    uint16_t tx_seq;   /* next frame to put on the wire (go-back-N pointer) */
} st_ring_t;

void st_ring_init(st_ring_t *r);
/* Room for one more frame? (at most ST_RING_FRAMES frames unacknowledged) */
int st_ring_has_room(const st_ring_t *r);
/* Sequence and store a frame; returns 0, or -1 when the ring is full. */
int st_ring_push(st_ring_t *r, uint8_t type, const uint8_t *payload, uint8_t len);
/* Cumulative acknowledgement up to (not including) seq; ignored when out of range. */
void st_ring_ack(st_ring_t *r, uint16_t seq);
/* NAK: acknowledge before seq and rewind transmission to seq.
 * Returns 0, or ST_ERR_LOST / ST_ERR_NAK_RANGE. */
int st_ring_nak(st_ring_t *r, uint16_t seq);
/* Wire form of the next frame to send; returns its length or 0 when nothing is pending. */
size_t st_ring_next_wire(st_ring_t *r, uint8_t *wire);

#endif
