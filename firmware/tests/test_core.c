/* C unit tests of the firmware core: the shared protocol vectors, fixed-point helpers, the
 * link ring buffer and whole procedures on the host HAL. Prints "N passed, N failed". */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "hal_host.h"
#include "st_cobs.h"
#include "st_crc16.h"
#include "st_fixed.h"
#include "st_link.h"
#include "vectors.h"

static int passed, failed;
#define CHECK(cond, ...)                                                     \
    do {                                                                     \
        if (cond) {                                                          \
            passed++;                                                        \
        } else {                                                             \
            failed++;                                                        \
            printf("FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond);           \
            printf(__VA_ARGS__);                                             \
            printf("\n");                                                    \
        }                                                                    \
    } while (0)

/* ------------------------------------------------------------------ vectors */
static void test_vectors(const char *path)
{
    vec_t *vs;
    int n = vec_load(path, &vs), i, nc = 0, nb = 0, nf = 0, nbad = 0;
    CHECK(n > 20, "vectors loaded: %d", n);
    for (i = 0; i < n; i++) {
        const vec_t *v = &vs[i];
        const char *kind = vec_get(v, "kind");
        uint8_t a[600], b[600], w[ST_WIRE_MAX + 8];
        int la, lb;
        if (!kind) continue;
        if (strcmp(kind, "crc16") == 0) {
            la = vec_hex(vec_get(v, "data_hex"), a, sizeof a);
            CHECK(la >= 0 && st_crc16(a, (size_t)la) == (uint16_t)vec_num(v, "crc"),
                  "crc16 of %s", vec_get(v, "data_hex"));
            nc++;
        } else if (strcmp(kind, "cobs") == 0) {
            size_t le;
            la = vec_hex(vec_get(v, "raw_hex"), a, sizeof a);
            lb = vec_hex(vec_get(v, "encoded_hex"), b, sizeof b);
            {
                uint8_t enc[700], dec[600];
                int ld;
                le = st_cobs_encode(a, (size_t)la, enc);
                CHECK(le == (size_t)lb && memcmp(enc, b, le) == 0, "cobs encode %s",
                      vec_get(v, "raw_hex"));
                ld = st_cobs_decode(b, (size_t)lb, dec, sizeof dec);
                CHECK(ld == la && memcmp(dec, a, (size_t)la) == 0, "cobs decode %s",
                      vec_get(v, "encoded_hex"));
            }
            nb++;
        } else if (strcmp(kind, "frame") == 0) {
            st_frame_t f;
            size_t lw;
            la = vec_hex(vec_get(v, "payload_hex"), a, sizeof a);
            lb = vec_hex(vec_get(v, "wire_hex"), b, sizeof b);
            lw = st_frame_encode((uint8_t)vec_num(v, "type"), (uint16_t)vec_num(v, "seq"), a,
                                 (uint8_t)la, w);
            CHECK(lw == (size_t)lb && memcmp(w, b, lw) == 0, "frame encode %s",
                  vec_get(v, "name"));
            CHECK(st_frame_decode(b, (size_t)lb - 1, &f) == 0 && f.type == vec_num(v, "type") &&
                      f.seq == vec_num(v, "seq") && f.len == la &&
                      memcmp(f.payload, a, (size_t)la) == 0,
                  "frame decode %s", vec_get(v, "name"));
            nf++;
        } else if (strcmp(kind, "bad") == 0) {
            st_frame_t f;
            const char *err = vec_get(v, "error");
            int want = strcmp(err, "cobs") == 0 ? -1 : strcmp(err, "length") == 0 ? -2 : -3;
            la = vec_hex(vec_get(v, "block_hex"), a, sizeof a);
            CHECK(st_frame_decode(a, (size_t)la, &f) == want, "bad frame %s -> %s",
                  vec_get(v, "name"), err);
            nbad++;
        }
    }
    CHECK(nc >= 3 && nb >= 6 && nf >= 10 && nbad >= 4, "vector counts %d %d %d %d", nc, nb, nf,
          nbad);
    free(vs);
}

/* ------------------------------------------------------------------ fixed point */
static void test_fixed(void)
{
    uint16_t m, k;
    double worst = 0;
    for (m = 0; m < 1000; m++) {
        double want = pow(10.0, m / 1000.0) * 4096.0;
        double err = fabs(st_pow10_milli_q12(m) - want) / want;
        if (err > worst) worst = err;
    }
    CHECK(worst < 4e-4, "pow10 worst relative error %g", worst);
    {
        uint32_t prev = 0;
        int mono = 1;
        double w2 = 0;
        for (k = 0; k < 60; k++) {
            uint32_t t = st_log_time_us(100, 10, k);
            double want = 100.0 * pow(10.0, k / 10.0);
            double err = (fabs(t - want) - 0.5) / want;
            if (err > w2) w2 = err;
            if (t <= prev) mono = 0;
            prev = t;
        }
        CHECK(mono, "log schedule strictly increasing");
        CHECK(w2 < 2e-3, "log schedule worst relative error %g", w2);
        CHECK(st_log_time_us(100, 10, 0) == 100 && st_log_time_us(100, 10, 10) == 1000 &&
                  st_log_time_us(100, 10, 50) == 10000000U,
              "decade points exact");
        CHECK(st_log_count(100, 10, 60000000U) == 58, "count to 60 s: %u",
              st_log_count(100, 10, 60000000U));
        CHECK(st_log_count(100, 10, 100) == 1, "count of one point");
        CHECK(st_log_time_us(1000000000U, 10, 20) == 0xFFFFFFFFU, "saturation");
    }
    CHECK(st_period_ns(25000000U) == 40000U, "25 kHz -> %u ns", st_period_ns(25000000U));
    CHECK(st_period_ns(3000000U) == 333333U, "3 kHz -> %u ns", st_period_ns(3000000U));
    CHECK(st_period_ns(500000U) == 2000000U, "500 Hz");
    CHECK(st_on_ns(40000U, 200000U) == 8000U, "20 %% of 40 us");
    CHECK(st_on_ns(2000000000U, 999000U) == 1998000000U, "99.9 %% of 2 s: %u",
          st_on_ns(2000000000U, 999000U));
    CHECK(st_current_for_power(94000U, 700000U) == 134285U, "I for 94 mW at 0.7 V: %u",
          st_current_for_power(94000U, 700000U));
    CHECK(st_current_for_power(20000000U, 900000U) == 22222222U, "I for 20 W at 0.9 V");
    CHECK(st_dac_for_current(125000U, 250000U, 1023) == 512, "half-scale DAC");
    CHECK(st_dac_for_current(500000U, 250000U, 1023) == 1023, "DAC clamps");
    {
        st_conv_t tsp = {-78125, 1600000, 800};
        CHECK(st_convert(&tsp, 20) == 47, "TSP code 20 -> %d uV", st_convert(&tsp, 20));
        CHECK(st_convert(&tsp, 1023) == -97902, "TSP full scale -> %d", st_convert(&tsp, 1023));
    }
}

/* ------------------------------------------------------------------ ring */
static void test_ring(void)
{
    static st_ring_t r;
    uint8_t wire[ST_WIRE_MAX], p = 0xAB;
    st_frame_t f;
    unsigned i;
    size_t n;
    st_ring_init(&r);
    for (i = 0; i < ST_RING_FRAMES; i++) {
        CHECK(st_ring_push(&r, ST_MSG_STATUS, &p, 1) == 0, "push %u", i);
    }
    CHECK(st_ring_push(&r, ST_MSG_STATUS, &p, 1) == -1, "ring full refuses");
    for (i = 0; i < ST_RING_FRAMES; i++) {
        n = st_ring_next_wire(&r, wire);
        CHECK(n > 0 && st_frame_decode(wire, n - 1, &f) == 0 && f.seq == i, "send %u", i);
    }
    CHECK(st_ring_next_wire(&r, wire) == 0, "nothing more to send");
    st_ring_ack(&r, 2);
    CHECK(st_ring_has_room(&r), "room after ack");
    CHECK(st_ring_nak(&r, 1) == ST_ERR_LOST, "nak before the ack is lost");
    CHECK(st_ring_nak(&r, ST_RING_FRAMES + 9) == ST_ERR_NAK_RANGE, "nak beyond next_seq");
    CHECK(st_ring_nak(&r, 3) == 0, "nak 3");
    n = st_ring_next_wire(&r, wire);
    CHECK(n > 0 && st_frame_decode(wire, n - 1, &f) == 0 && f.seq == 3, "resend from 3");
    /* wrap-around of the 16-bit sequence */
    st_ring_init(&r);
    r.next_seq = r.acked = r.tx_seq = 0xFFFE;
    for (i = 0; i < 4; i++) st_ring_push(&r, ST_MSG_STATUS, &p, 1);
    st_ring_ack(&r, 0x0001);
    CHECK(r.acked == 1 && r.next_seq == 2, "ack across wrap: acked %u", r.acked);
    CHECK(st_ring_nak(&r, 0xFFFF) == ST_ERR_LOST, "nak across wrap");
}

/* ------------------------------------------------------------------ core on the host HAL */
typedef struct {
    st_frame_t f[512];
    int n;
} frames_t;

static void collect(hh_device_t *d, frames_t *out)
{
    st_rx_t rx;
    uint32_t i;
    st_rx_init(&rx);
    for (i = 0; i < d->s.tx_len; i++) {
        if (out->n < 512 && st_rx_feed(&rx, d->s.tx[i], &out->f[out->n])) out->n++;
    }
    d->s.tx_len = 0;
}

static void send(hh_device_t *d, uint8_t type, uint16_t seq, const uint8_t *pl, uint8_t len)
{
    uint8_t w[ST_WIRE_MAX];
    size_t n = st_frame_encode(type, seq, pl, len, w);
    hh_rx(d, w, (uint32_t)n);
    hh_poll(d);
}

static void board(hh_device_t *d)
{
    st_board_t b = {{{-78125, 1600000, 800}, {78125, 0, 16}, {78125, 0, 160},
                     {78125, 0, 1600}, {78125, -8000000, 800}},
                    250000U, 1023, 700000U, -10000, 90000, 0, 10, "test", 1000U, 0, 0};
    d->s.board = b;
}

/* run the device, answering ADC requests with fixed codes, until idle or a step limit */
static int run(hh_device_t *d, frames_t *out, uint16_t next_ack, int max_steps)
{
    static const uint16_t codes[ST_NCH] = {40, 143, 275, 256, 300};
    int steps = 0, adc = 0;
    uint32_t i, adc_t = 0;
    while (steps++ < max_steps) {
        for (i = 0; i < d->s.n_ops; i++) {
            hh_op_t *o = &d->s.ops[i];
            if (o->op == HH_OP_ADC_AT) { adc = 1; adc_t = o->a; }
            if (o->op == HH_OP_ADC_ON_PHASE) { adc = 1; adc_t = o->t_us + 10; }
            if (o->op == HH_OP_ADC_AFTER_CUT) { adc = 1; adc_t = o->t_us + 50 + o->a; }
        }
        d->s.n_ops = 0;
        if (adc && (!d->s.wake_set || (int32_t)(adc_t - d->s.wake_us) <= 0)) {
            if ((int32_t)(adc_t - d->s.now_us) > 0) d->s.now_us = adc_t;
            adc = 0;
            hh_adc(d, codes);
        } else if (d->s.wake_set) {
            if ((int32_t)(d->s.wake_us - d->s.now_us) > 0) d->s.now_us = d->s.wake_us;
        } else {
            break; /* idle */
        }
        hh_poll(d);
        {
            int before = out->n;
            collect(d, out);
            if (out->n != before) {
                uint8_t pl[2];
                next_ack = (uint16_t)(out->f[out->n - 1].seq + 1u);
                st_put_u16(pl, next_ack);
                send(d, ST_CMD_ACK, 0, pl, 2);
            }
        }
    }
    collect(d, out);
    return steps;
}

static void test_core(void)
{
    hh_device_t *d = hh_new();
    static frames_t fr;
    uint8_t pl[32];
    int i, samples = 0, curve = 0, power = 0, steady = 0, contiguous = 1, done = -1;
    uint32_t last_index = 0xFFFFFFFFU;
    board(d);
    hh_init(d);
    d->s.now_us = 12345;

    /* HELLO -> ACK + INFO */
    pl[0] = 1;
    send(d, ST_CMD_HELLO, 77, pl, 1);
    fr.n = 0;
    collect(d, &fr);
    CHECK(fr.n == 2, "hello answered by 2 frames, got %d", fr.n);
    CHECK(fr.f[0].type == ST_MSG_ACK && fr.f[0].seq == 0 && st_get_u16(fr.f[0].payload) == 77 &&
              fr.f[0].payload[3] == ST_OK,
          "ack of hello");
    CHECK(fr.f[1].type == ST_MSG_INFO && fr.f[1].seq == 1 &&
              fr.f[1].payload[0] == ST_PROTO_VERSION && fr.f[1].payload[1] == ST_FW_MAJOR &&
              st_get_u32(fr.f[1].payload + 8) == ST_SETTLE_MAX_MS &&
              st_get_u32(fr.f[1].payload + 12) == 1000U &&
              memcmp(fr.f[1].payload + ST_LEN_INFO_FIXED, "test", 4) == 0,
          "info");
    /* the same command again is not executed twice */
    send(d, ST_CMD_HELLO, 77, pl, 1);
    fr.n = 0;
    collect(d, &fr);
    CHECK(fr.n == 0, "duplicate command ignored (%d frames)", fr.n);
    /* NAK 0 resends both */
    st_put_u16(pl, 0);
    send(d, ST_CMD_NAK, 78, pl, 2);
    fr.n = 0;
    collect(d, &fr);
    CHECK(fr.n == 2 && fr.f[0].seq == 0 && fr.f[1].seq == 1, "nak resends from 0");
    /* NAK at next_seq -> SYNC (unsequenced) */
    st_put_u16(pl, 2);
    send(d, ST_CMD_NAK, 79, pl, 2);
    fr.n = 0;
    collect(d, &fr);
    CHECK(fr.n == 1 && fr.f[0].type == ST_MSG_SYNC && fr.f[0].seq == 2 &&
              st_get_u16(fr.f[0].payload) == 77 && fr.f[0].payload[2] == 0,
          "sync when nothing to resend");
    /* NAK beyond -> ERROR */
    st_put_u16(pl, 9);
    send(d, ST_CMD_NAK, 80, pl, 2);
    fr.n = 0;
    collect(d, &fr);
    CHECK(fr.n == 1 && fr.f[0].type == ST_MSG_ERROR && fr.f[0].payload[0] == ST_ERR_NAK_RANGE,
          "error for a nak beyond next_seq");
    /* unknown command, bad length, bad parameter */
    send(d, 0x3F, 81, pl, 0);
    send(d, ST_CMD_RTH, 82, pl, 3);
    memset(pl, 0, 12);
    send(d, ST_CMD_RTH, 83, pl, 12);
    fr.n = 0;
    collect(d, &fr);
    CHECK(fr.n == 3 && fr.f[0].payload[3] == ST_E_UNKNOWN && fr.f[1].payload[3] == ST_E_LENGTH &&
              fr.f[2].payload[3] == ST_E_PARAM,
          "command errors (%d frames)", fr.n);

    /* a cooling run: 2 s settle, 4 pre-cut readings, curve 100 us .. 1 s at 10/decade */
    st_put_u32(pl, 94000);
    st_put_u32(pl + 4, 2000);
    st_put_u16(pl + 8, 100);
    st_put_u16(pl + 10, 4);
    st_put_u32(pl + 12, 100);
    st_put_u32(pl + 16, 1000);
    pl[20] = 10;
    send(d, ST_CMD_COOLING, 90, pl, 21);
    CHECK(d->core.p.power_uw == 94000 && d->core.p.t_last_ms == 1000 &&
              d->core.p.per_decade == 10 && d->core.p.total == 41,
          "cooling parameters parsed (total %u)", d->core.p.total);
    /* busy while running */
    send(d, ST_CMD_RTH, 91, pl, 12);
    fr.n = 0;
    run(d, &fr, 0, 100000);
    for (i = 0; i < fr.n; i++) {
        const st_frame_t *f = &fr.f[i];
        if (f->type == ST_MSG_ACK && st_get_u16(f->payload) == 91) {
            CHECK(f->payload[3] == ST_E_BUSY, "busy");
        }
        if (f->type == ST_MSG_SAMPLE) {
            uint32_t idx = st_get_u32(f->payload + 2);
            if (last_index != 0xFFFFFFFFU && idx != last_index + 1) contiguous = 0;
            last_index = idx;
            samples++;
            if (f->payload[1] == ST_KIND_CURVE) curve++;
            if (f->payload[1] == ST_KIND_POWER) power++;
            if (f->payload[1] == ST_KIND_STEADY) {
                steady++;
                CHECK(st_get_u32(f->payload + 6) == 100, "steady t_us = window");
            }
            if (i > 0 && f->payload[1] == ST_KIND_CURVE && curve == 1) {
                CHECK(st_get_u32(f->payload + 6) == 100, "first curve point at 100 us");
            }
            /* conversions: TSP code 40 -> (40 * -78125 + 1600000) / 800 */
            CHECK((int32_t)st_get_u32(f->payload + 10) == -1906, "tsp uV %d",
                  (int32_t)st_get_u32(f->payload + 10));
            CHECK(st_get_u16(f->payload + 30) == 40, "raw code kept");
        }
        if (f->type == ST_MSG_DONE) {
            done = f->payload[1];
            CHECK(st_get_u16(f->payload + 2) == samples, "done counts %u samples of %d",
                  st_get_u16(f->payload + 2), samples);
            CHECK(st_get_u32(f->payload + 4) == 0, "first index 0");
        }
    }
    CHECK(done == 0, "cooling done ok (%d)", done);
    CHECK(curve == 41 && power == 4 && steady == 4, "curve %d power %d steady %d", curve, power,
          steady);
    CHECK(contiguous, "sample indices contiguous");
    CHECK(!hh_busy(d), "idle after done");

    /* a new HELLO ends a running procedure and starts a new session */
    memset(pl, 0, 24);
    st_put_u32(pl, 94000);
    st_put_u32(pl + 4, 1000000);  /* 1 kHz */
    st_put_u32(pl + 8, 500000);   /* 50 % */
    st_put_u32(pl + 12, 60000);
    st_put_u16(pl + 16, 100);
    st_put_u16(pl + 18, 4);
    st_put_u16(pl + 20, 100);
    send(d, ST_CMD_PWM, 95, pl, 22);
    CHECK(hh_busy(d), "pwm running");
    pl[0] = 1;
    send(d, ST_CMD_HELLO, 96, pl, 1);
    fr.n = 0;
    collect(d, &fr);
    CHECK(!hh_busy(d), "hello aborted the procedure");
    CHECK(fr.n >= 2 && fr.f[fr.n - 2].type == ST_MSG_ACK && fr.f[fr.n - 2].seq == 0 &&
              fr.f[fr.n - 1].type == ST_MSG_INFO && fr.f[fr.n - 1].seq == 1,
          "new session numbering");
    hh_free(d);
}

/* Settling longer than the 32-bit microsecond clock's signed range (2147.48 s) and its wrap
 * (4294.97 s): an RTH run must report STATUS heartbeats up to the full settle time before its
 * first sample (32-bit arithmetic used to skip settling above 2147 s). */
static uint32_t settle_then_first_sample(uint32_t settle_ms, uint32_t *before_ms)
{
    hh_device_t *d = hh_new();
    static frames_t fr;
    uint8_t pl[12];
    int i, chunk;
    uint32_t status_ms = 0, first = 0;
    board(d);
    hh_init(d);
    d->s.now_us = 0xFFF00000U; /* just before the clock wraps */
    pl[0] = ST_PROTO_VERSION;
    send(d, ST_CMD_HELLO, 1, pl, 1);
    st_put_u32(pl, 94000);
    st_put_u32(pl + 4, settle_ms);
    st_put_u16(pl + 8, 100);
    st_put_u16(pl + 10, 2);
    send(d, ST_CMD_RTH, 2, pl, 12);
    for (chunk = 0; chunk < 10000 && !first; chunk++) { /* frames_t holds 512 frames */
        fr.n = 0;
        run(d, &fr, 0, 200);
        for (i = 0; i < fr.n && !first; i++) {
            if (fr.f[i].type == ST_MSG_STATUS) status_ms = st_get_u32(fr.f[i].payload + 6);
            if (fr.f[i].type == ST_MSG_ACK && st_get_u16(fr.f[i].payload) == 2) {
                CHECK(fr.f[i].payload[3] == ST_OK, "rth with settle %u ms accepted", settle_ms);
            }
            if (fr.f[i].type == ST_MSG_SAMPLE) first = 1;
        }
    }
    CHECK(first, "samples after a settle of %u ms", settle_ms);
    *before_ms = status_ms;
    hh_free(d);
    return status_ms;
}

static void test_long_settle(void)
{
    static const uint32_t settle[] = {2147000U, 2148000U, 2200000U, 4295000U, 5000000U};
    hh_device_t *d = hh_new();
    static frames_t fr;
    uint8_t pl[12];
    unsigned i;
    for (i = 0; i < sizeof settle / sizeof settle[0]; i++) {
        uint32_t last;
        settle_then_first_sample(settle[i], &last);
        CHECK(last + ST_STATUS_MS >= settle[i] && last <= settle[i],
              "settle %u ms: last heartbeat before the first sample at %u ms", settle[i], last);
    }
    /* the limit INFO reports: at it accepted, above it refused */
    board(d);
    hh_init(d);
    pl[0] = ST_PROTO_VERSION;
    send(d, ST_CMD_HELLO, 1, pl, 1);
    st_put_u32(pl, 94000);
    st_put_u32(pl + 4, ST_SETTLE_MAX_MS + 1U);
    st_put_u16(pl + 8, 100);
    st_put_u16(pl + 10, 2);
    send(d, ST_CMD_RTH, 2, pl, 12);
    st_put_u32(pl + 4, ST_SETTLE_MAX_MS);
    send(d, ST_CMD_RTH, 3, pl, 12);
    fr.n = 0;
    collect(d, &fr);
    CHECK(fr.n >= 4 && fr.f[2].type == ST_MSG_ACK && fr.f[2].payload[3] == ST_E_PARAM &&
              fr.f[3].type == ST_MSG_ACK && fr.f[3].payload[3] == ST_OK,
          "settle limit %lu ms: above refused, at accepted", (unsigned long)ST_SETTLE_MAX_MS);
    hh_free(d);
}

/* FORWARD: n pulses at each of count currents on the fixture, one reading in each pulse's
 * middle; the heater off between them; malformed commands refused. */
static void test_forward(void)
{
    hh_device_t *d = hh_new();
    static frames_t fr;
    uint8_t pl[ST_LEN_FORWARD_FIXED + 4 * ST_FORWARD_MAX];
    int i, forward = 0, other = 0, done = -1, pwm_on = 0, cuts = 0, fixture_set = 0;
    uint32_t i_ua[3] = {5000U, 100000U, 250000U};
    board(d);
    hh_init(d);
    pl[0] = ST_PROTO_VERSION;
    send(d, ST_CMD_HELLO, 1, pl, 1);
    st_put_u32(pl, 45000);  /* 45 degC */
    st_put_u32(pl + 4, 2000);
    st_put_u16(pl + 8, 40); /* 40 us pulses */
    st_put_u16(pl + 10, 2);
    st_put_u16(pl + 12, 20);
    pl[14] = 3;
    for (i = 0; i < 3; i++) st_put_u32(pl + 15 + 4 * i, i_ua[i]);
    send(d, ST_CMD_FORWARD, 2, pl, 15 + 12);
    CHECK(d->core.p.proc == ST_PROC_FORWARD && d->core.p.total == 6 &&
              d->core.p.dac[1] == st_dac_for_current(100000U, 250000U, 1023),
          "forward parameters parsed (total %u)", d->core.p.total);
    for (i = 0; i < (int)d->s.n_ops; i++) {
        if (d->s.ops[i].op == HH_OP_FIXTURE && d->s.ops[i].a > 0) fixture_set = 1;
    }
    CHECK(fixture_set, "the fixture is set to the setpoint");
    fr.n = 0;
    {
        /* the run loop answers ADC requests; count the pulses it sees as PWM ops */
        int steps = 0;
        while (steps++ < 100000 && hh_busy(d)) {
            uint32_t k;
            for (k = 0; k < d->s.n_ops; k++) {
                if (d->s.ops[k].op == HH_OP_PWM && d->s.ops[k].a == 80000U &&
                    d->s.ops[k].b == 40000U) pwm_on++;
                if (d->s.ops[k].op == HH_OP_CUT && d->s.ops[k].a == 1) cuts++;
            }
            run(d, &fr, 0, 1);
        }
        run(d, &fr, 0, 50);
    }
    for (i = 0; i < fr.n; i++) {
        const st_frame_t *f = &fr.f[i];
        if (f->type == ST_MSG_SAMPLE) {
            if (f->payload[0] == ST_PROC_FORWARD && f->payload[1] == ST_KIND_FORWARD &&
                st_get_u32(f->payload + 6) == 20U) {
                forward++;
            } else {
                other++;
            }
        }
        if (f->type == ST_MSG_DONE) {
            done = f->payload[1];
            CHECK(st_get_u16(f->payload + 2) == 6, "done counts 6 samples");
        }
    }
    CHECK(done == 0 && forward == 6 && other == 0, "forward: done %d, %d readings, %d other",
          done, forward, other);
    CHECK(pwm_on == 6 && cuts == 6, "one 40 us pulse per reading, each cut (%d, %d)", pwm_on,
          cuts);
    /* refused: bad length, no current, a current above full scale */
    send(d, ST_CMD_FORWARD, 3, pl, 15 + 8);
    pl[14] = 0;
    send(d, ST_CMD_FORWARD, 4, pl, 15);
    pl[14] = 1;
    st_put_u32(pl + 15, 250001U);
    send(d, ST_CMD_FORWARD, 5, pl, 15 + 4);
    fr.n = 0;
    collect(d, &fr);
    CHECK(fr.n == 3 && fr.f[0].payload[3] == ST_E_LENGTH && fr.f[1].payload[3] == ST_E_PARAM &&
              fr.f[2].payload[3] == ST_E_PARAM,
          "forward refusals (%d frames)", fr.n);
    hh_free(d);
}

/* The coupling procedure on an array board of 4 ports: heat port 2, read all. */
static void test_coupling(void)
{
    hh_device_t *d = hh_new();
    static frames_t fr;
    uint8_t pl[32];
    int i, cold = 0, power = 0, steady = 0, curve = 0, plain = 0, done = -1, total = 0;
    int order_ok = 1, last_port = -1;
    uint32_t last_t = 0;
    board(d);
    d->s.board.ports = 4;
    d->s.board.scan_us = 20;
    hh_init(d);
    pl[0] = ST_PROTO_VERSION;
    send(d, ST_CMD_HELLO, 1, pl, 1);
    fr.n = 0;
    collect(d, &fr);
    CHECK(fr.n == 2 && st_get_u16(fr.f[1].payload + 6) >> ST_CAP_PORTS_SHIFT == 4,
          "INFO reports 4 ports");
    pl[0] = 2; /* heater */
    pl[1] = 4; /* ports read */
    st_put_u32(pl + 2, 250000);
    st_put_u32(pl + 6, 1000);
    st_put_u16(pl + 10, 100);
    st_put_u16(pl + 12, 2);
    st_put_u32(pl + 14, 100);
    st_put_u32(pl + 18, 100);
    pl[22] = 10;
    send(d, ST_CMD_COUPLING, 2, pl, ST_LEN_COUPLING);
    CHECK(hh_busy(d) && d->core.p.proc == ST_PROC_COUPLING && d->core.p.heater == 2,
          "coupling started");
    fr.n = 0;
    run(d, &fr, 0, 100000);
    for (i = 0; i < fr.n; i++) {
        const st_frame_t *f = &fr.f[i];
        if (f->type == ST_MSG_SAMPLE) plain++;
        if (f->type == ST_MSG_ARRAY_SAMPLE) {
            uint8_t kind = f->payload[1], port = f->payload[ST_LEN_SAMPLE];
            uint32_t t = st_get_u32(f->payload + 6);
            total++;
            CHECK(f->len == ST_LEN_ARRAY_SAMPLE && port < 4, "array sample length and port");
            if (kind == ST_KIND_COLD) cold++;
            if (kind == ST_KIND_POWER) {
                power++;
                CHECK(port == 2, "power reading of the heated port (%u)", port);
            }
            if (kind == ST_KIND_STEADY) {
                steady++;
                CHECK(t == 100u + 20u * port, "steady reading of port %u at %u us", port, t);
            }
            if (kind == ST_KIND_CURVE) {
                curve++;
                if (port == 0 && last_port >= 0 && (last_port != 3 || t < last_t + 20u)) {
                    order_ok = 0; /* a scan reads every port; the next starts after it */
                }
                if (port > 0 && (port != last_port + 1 || t != last_t + 20u)) order_ok = 0;
                last_port = port;
                last_t = t;
            }
        }
        if (f->type == ST_MSG_DONE) {
            done = f->payload[1];
            CHECK(st_get_u16(f->payload + 2) == total, "done counts %u of %d",
                  st_get_u16(f->payload + 2), total);
        }
    }
    CHECK(done == 0 && plain == 0, "coupling done ok (%d), only array samples (%d)", done, plain);
    CHECK(cold == 8 && power == 2 && steady == 8, "cold %d power %d steady %d", cold, power,
          steady);
    CHECK(curve > 0 && curve % 4 == 0 && order_ok, "curve scans complete and ordered (%d)",
          curve);
    /* a single-heater board refuses it */
    d->s.board.ports = 0;
    send(d, ST_CMD_COUPLING, 3, pl, ST_LEN_COUPLING);
    fr.n = 0;
    collect(d, &fr);
    CHECK(fr.n == 1 && fr.f[0].type == ST_MSG_ACK && fr.f[0].payload[3] == ST_E_PARAM,
          "no coupling without ports");
    hh_free(d);
}

int main(int argc, char **argv)
{
    test_vectors(argc > 1 ? argv[1] : "protocol_vectors.json");
    test_fixed();
    test_ring();
    test_core();
    test_long_settle();
    test_forward();
    test_coupling();
    printf("%d passed, %d failed\n", passed, failed);
    return failed ? 1 : 0;
}
