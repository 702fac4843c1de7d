#include <string.h>
#include "st_core_int.h"
#include "st_fixed.h"
#include "st_hal.h"

uint8_t st_fw_version[3] = {ST_FW_MAJOR, ST_FW_MINOR, ST_FW_PATCH};

/* Procedures on the calibration fixture (no heating power regulated while they settle). */
static int on_fixture(const st_proc_t *p)
{
    return p->proc == ST_PROC_CAL || p->proc == ST_PROC_FORWARD;
}

static int32_t elapsed(uint32_t now, uint32_t then)
{
    return (int32_t)(now - then);
}

static int due(uint32_t now, uint32_t t)
{
    return elapsed(now, t) >= 0;
}

/* ------------------------------------------------------------------ output */
static void push(st_core_t *c, uint8_t type, const uint8_t *payload, uint8_t len)
{
    (void)st_ring_push(&c->ring, type, payload, len);
}

static uint8_t ring_free(const st_core_t *c)
{
    return (uint8_t)(ST_RING_FRAMES - (uint16_t)(c->ring.next_seq - c->ring.acked));
}

static void send_ack(st_core_t *c, uint16_t seq, uint8_t type, uint8_t status)
{
    /* kept until there is room in the ring (the host acknowledges before commanding, so
     * normally at once) */
    st_put_u16(c->ack, seq);
    c->ack[2] = type;
    c->ack[3] = status;
    c->ack_pending = 1;
    if (st_ring_push(&c->ring, ST_MSG_ACK, c->ack, 4) == 0) {
        c->ack_pending = 0;
    }
}

static void send_info(st_core_t *c)
{
    const st_board_t *bd = hal_board();
    uint8_t b[ST_MAX_PAYLOAD];
    uint8_t n = ST_LEN_INFO_FIXED, i;
    b[0] = ST_PROTO_VERSION;
    b[1] = st_fw_version[0];
    b[2] = st_fw_version[1];
    b[3] = st_fw_version[2];
    b[4] = bd->adc_bits;
    b[5] = (uint8_t)ST_RING_FRAMES;
    st_put_u16(b + 6, (uint16_t)(bd->caps | (bd->ports > 1 ? bd->ports << ST_CAP_PORTS_SHIFT : 0)));
    st_put_u32(b + 8, ST_SETTLE_MAX_MS);
    st_put_u32(b + 12, bd->i_sense_ua);
    for (i = 0; i < sizeof bd->name && bd->name[i]; i++) {
        b[n++] = (uint8_t)bd->name[i];
    }
    push(c, ST_MSG_INFO, b, n);
}

static void send_status(st_core_t *c)
{
    uint8_t b[10];
    if (ring_free(c) <= ST_RESERVE) {
        return; /* a heartbeat is worth nothing when the host is behind */
    }
    b[0] = c->p.proc;
    b[1] = c->p.state;
    st_put_u16(b + 2, c->p.k);
    st_put_u16(b + 4, c->p.total);
    st_put_u32(b + 6, c->p.run_ms);
    push(c, ST_MSG_STATUS, b, 10);
}

static void send_done(st_core_t *c)
{
    uint8_t b[8];
    b[0] = c->p.proc;
    b[1] = c->p.status;
    st_put_u16(b + 2, c->p.n_samples);
    st_put_u32(b + 4, c->p.first_index);
    push(c, ST_MSG_DONE, b, 8);
}

/* Convert the oldest raw sample and sequence it (keeping room for control frames). */
static void drain_fifo(st_core_t *c)
{
    const st_board_t *bd = hal_board();
    while (c->f_count && ring_free(c) > ST_RESERVE) {
        st_raw_t *s = &c->fifo[c->f_head];
        uint8_t b[ST_LEN_ARRAY_SAMPLE];
        uint8_t i;
        b[0] = c->p.proc;
        b[1] = s->kind;
        st_put_u32(b + 2, c->sample_index++);
        st_put_u32(b + 6, s->t_us);
        for (i = 0; i < ST_NCH; i++) {
            st_put_u32(b + 10 + 4 * i, (uint32_t)st_convert(&bd->ch[i], s->code[i]));
            st_put_u16(b + 30 + 2 * i, s->code[i]);
        }
        if (c->p.proc == ST_PROC_COUPLING) {
            b[ST_LEN_SAMPLE] = s->port;
            push(c, ST_MSG_ARRAY_SAMPLE, b, ST_LEN_ARRAY_SAMPLE);
        } else {
            push(c, ST_MSG_SAMPLE, b, ST_LEN_SAMPLE);
        }
        c->f_head = (uint8_t)((c->f_head + 1u) % ST_FIFO_LEN);
        c->f_count--;
    }
}

static void flush_wire(st_core_t *c)
{
    size_t n;
    for (;;) {
        if (hal_uart_space() < ST_WIRE_MAX) {
            return;
        }
        if (c->pending_err) {
            uint8_t b[3];
            b[0] = c->pending_err_code;
            st_put_u16(b + 1, c->pending_err_detail);
            n = st_frame_encode(ST_MSG_ERROR, c->ring.next_seq, b, 3, c->wire);
            c->pending_err = 0;
        } else if (c->pending_sync) {
            uint8_t b[3];
            st_put_u16(b, c->last_cmd_seq);
            b[2] = st_core_busy(c);
            n = st_frame_encode(ST_MSG_SYNC, c->ring.next_seq, b, 3, c->wire);
            c->pending_sync = 0;
        } else {
            n = st_ring_next_wire(&c->ring, c->wire);
            if (n == 0) {
                return;
            }
        }
        hal_uart_write(c->wire, (uint16_t)n);
    }
}

/* ------------------------------------------------------------------ heater and ADC */

static void regulate(st_core_t *c)
{
    const st_board_t *bd = hal_board();
    int32_t vd = st_convert(&bd->ch[ST_CH_VD], c->p.codes[ST_CH_VD]);
    uint32_t i_ua;
    if (vd < 100000L) { /* no sensible diode voltage: keep the setting */
        return;
    }
    i_ua = st_current_for_power(c->p.power_uw, (uint32_t)vd);
    hal_heater_dac(st_dac_for_current(i_ua, bd->i_full_ua, bd->dac_max));
}

/* ------------------------------------------------------------------ commands */
static void fixture(const st_board_t *bd, int32_t setpoint_mc)
{
    int32_t span = bd->fixture_max_mc - bd->fixture_min_mc;
    uint32_t num = (uint32_t)(setpoint_mc - bd->fixture_min_mc);
    hal_fixture_dac(st_dac_for_current(num, (uint32_t)span, bd->dac_max));
}

static uint8_t start(st_core_t *c, uint8_t type, const uint8_t *b, uint8_t len)
{
    st_proc_t *p = &c->p;
    const st_board_t *bd = hal_board();
    uint32_t now = hal_now_us();
    memset(p, 0, sizeof *p);
    switch (type) {
    case ST_CMD_CALIBRATE:
        if (len != 12) return ST_E_LENGTH;
        p->proc = ST_PROC_CAL;
        p->setpoint_mc = (int32_t)st_get_u32(b);
        p->settle_ms = st_get_u32(b + 4);
        p->n = st_get_u16(b + 8);
        p->interval_ms = st_get_u16(b + 10);
        if (p->n == 0 || p->setpoint_mc < bd->fixture_min_mc ||
            p->setpoint_mc > bd->fixture_max_mc || p->settle_ms > ST_SETTLE_MAX_MS)
            return ST_E_PARAM;
        fixture(bd, p->setpoint_mc);
        st_heater_off();
        break;
    case ST_CMD_FORWARD: {
        uint8_t k;
        if (len < ST_LEN_FORWARD_FIXED || len != ST_LEN_FORWARD_FIXED + 4u * b[14])
            return ST_E_LENGTH;
        p->proc = ST_PROC_FORWARD;
        p->setpoint_mc = (int32_t)st_get_u32(b);
        p->settle_ms = st_get_u32(b + 4);
        p->window_us = st_get_u16(b + 8); /* the pulse */
        p->n = st_get_u16(b + 10);
        p->interval_ms = st_get_u16(b + 12);
        p->count = b[14];
        if (p->n == 0 || p->count == 0 || p->count > ST_FORWARD_MAX || p->window_us < 10 ||
            p->window_us > 4000 || p->interval_ms == 0 || p->setpoint_mc < bd->fixture_min_mc ||
            p->setpoint_mc > bd->fixture_max_mc || p->settle_ms > ST_SETTLE_MAX_MS ||
            (uint32_t)p->n * p->count > 0xFFFFu)
            return ST_E_PARAM;
        for (k = 0; k < p->count; k++) {
            uint32_t i_ua = st_get_u32(b + ST_LEN_FORWARD_FIXED + 4u * k);
            if (i_ua == 0 || i_ua > bd->i_full_ua) return ST_E_PARAM;
            p->dac[k] = st_dac_for_current(i_ua, bd->i_full_ua, bd->dac_max);
        }
        /* one pulse per period of twice its length; the cut ends it, the reading is in its
         * middle */
        p->on_ns = (uint32_t)p->window_us * 1000U;
        p->period_ns = 2U * p->on_ns;
        fixture(bd, p->setpoint_mc);
        st_heater_off();
        break;
    }
    case ST_CMD_RTH:
        if (len != 12) return ST_E_LENGTH;
        p->proc = ST_PROC_RTH;
        p->power_uw = st_get_u32(b);
        p->settle_ms = st_get_u32(b + 4);
        p->window_us = st_get_u16(b + 8);
        p->n = st_get_u16(b + 10);
        p->interval_ms = 0;
        /* 99.9 % duty: the off-phase of each period is the sample window */
        p->period_ns = (uint32_t)p->window_us * 1000000U;
        p->on_ns = p->period_ns - (uint32_t)p->window_us * 1000U;
        if (p->window_us < 10 || p->window_us > 4000 || p->n == 0 || p->power_uw == 0 ||
            p->settle_ms > ST_SETTLE_MAX_MS)
            return ST_E_PARAM;
        break;
    case ST_CMD_COOLING:
        if (len != 21) return ST_E_LENGTH;
        p->proc = ST_PROC_COOLING;
        p->power_uw = st_get_u32(b);
        p->settle_ms = st_get_u32(b + 4);
        p->window_us = st_get_u16(b + 8);
        p->n = st_get_u16(b + 10);
        p->t_first_us = st_get_u32(b + 12);
        p->t_last_ms = st_get_u32(b + 16);
        p->per_decade = b[20];
        p->interval_ms = 100;
        p->period_ns = 1000000U; /* dc: on-time = period */
        p->on_ns = p->period_ns;
        if (p->power_uw == 0 || p->per_decade == 0 || p->t_first_us < 10 ||
            p->t_last_ms > ST_CURVE_MAX_MS || p->t_last_ms * 1000U < p->t_first_us ||
            p->settle_ms > ST_SETTLE_MAX_MS)
            return ST_E_PARAM;
        p->total = st_log_count(p->t_first_us, p->per_decade, p->t_last_ms * 1000U);
        break;
    case ST_CMD_PWM: {
        uint32_t f, d;
        if (len != 22) return ST_E_LENGTH;
        p->proc = ST_PROC_PWM;
        p->power_uw = st_get_u32(b);
        f = st_get_u32(b + 4);
        d = st_get_u32(b + 8);
        p->settle_ms = st_get_u32(b + 12);
        p->window_us = st_get_u16(b + 16);
        p->n = st_get_u16(b + 18);
        p->interval_ms = st_get_u16(b + 20);
        if (f < 1000U || f > 200000000U || d == 0 || d > 1000000U || p->n == 0 ||
            p->power_uw == 0 || p->window_us > 4000 || p->settle_ms > ST_SETTLE_MAX_MS)
            return ST_E_PARAM;
        p->period_ns = st_period_ns(f);
        p->on_ns = st_on_ns(p->period_ns, d);
        if (p->on_ns == 0) return ST_E_PARAM;
        break;
    }
    case ST_CMD_COUPLING:
        return st_array_start(c, b, len);
    default:
        return ST_E_UNKNOWN;
    }
    if (!on_fixture(p)) {
        uint32_t i_ua = st_current_for_power(p->power_uw, bd->vd_nominal_uv);
        hal_fixture_dac(0); /* the device is off the calibration hot plate */
        hal_release();
        hal_heater_dac(st_dac_for_current(i_ua, bd->i_full_ua, bd->dac_max));
        hal_heater_pwm(p->period_ns, p->on_ns);
    }
    c->f_dropped = 0;
    p->t_start = now;
    p->t_clock = now;
    p->t_status = now + ST_STATUS_MS * 1000U;
    p->t_next = now + ST_CONTROL_TICK_MS * 1000U;
    if (p->proc == ST_PROC_FORWARD) {
        p->total = (uint16_t)(p->n * p->count);
    } else if (p->proc != ST_PROC_COOLING) {
        p->total = p->n;
    }
    p->state = S_SETTLE;
    return ST_OK;
}

static void handle(st_core_t *c, const st_frame_t *f)
{
    uint8_t st;
    switch (f->type) {
    case ST_CMD_ACK:
        if (f->len == 2) st_ring_ack(&c->ring, st_get_u16(f->payload));
        return;
    case ST_CMD_NAK:
        if (f->len == 2) {
            uint16_t seq = st_get_u16(f->payload);
            int e = (seq == c->ring.next_seq) ? 0 : st_ring_nak(&c->ring, seq);
            if (seq == c->ring.next_seq) {
                st_ring_ack(&c->ring, seq);
                c->pending_sync = 1; /* nothing to resend: tell the host where we are */
            } else if (e) {
                c->pending_err = 1;
                c->pending_err_code = (uint8_t)e;
                c->pending_err_detail = seq;
            }
        }
        return;
    default:
        break;
    }
    /* commands: execute each sequence number once */
    if (c->have_cmd && f->seq == c->last_cmd_seq) {
        return;
    }
    c->have_cmd = 1;
    c->last_cmd_seq = f->seq;
    switch (f->type) {
    case ST_CMD_HELLO:
        if (st_core_busy(c)) { /* a new session ends whatever the last one left running */
            st_heater_off();
            c->p.state = S_IDLE;
            c->p.proc = ST_PROC_NONE;
        }
        st_ring_init(&c->ring);
        c->ack_pending = 0;
        c->sample_index = 0;
        c->f_count = 0;
        send_ack(c, f->seq, f->type, ST_OK);
        send_info(c);
        return;
    case ST_CMD_ABORT:
        if (st_core_busy(c)) {
            st_heater_off();
            c->p.state = S_IDLE;
            c->p.proc = ST_PROC_NONE;
        }
        c->f_count = 0;
        send_ack(c, f->seq, f->type, ST_OK);
        return;
    default:
        if (st_core_busy(c)) {
            send_ack(c, f->seq, f->type, ST_E_BUSY);
            return;
        }
        st = start(c, f->type, f->payload, f->len);
        if (st != ST_OK) {
            c->p.state = S_IDLE;
            c->p.proc = ST_PROC_NONE;
            st_heater_off();
        }
        send_ack(c, f->seq, f->type, st);
        return;
    }
}

/* ------------------------------------------------------------------ procedures */

static void next_reading(st_core_t *c, uint32_t now)
{
    st_proc_t *p = &c->p;
    if (p->k >= p->n) {
        if (p->proc == ST_PROC_COOLING || p->proc == ST_PROC_COUPLING) {
            /* cut the power now and sample the cooling curve */
            hal_cut(0);
            hal_heater_pwm(0, 0);
            p->t_cut = now;
            p->k = 0;
            st_curve_next(c, 0);
            return;
        }
        st_finish(c, ST_OK);
        return;
    }
    hal_adc_on_phase();
    st_arm(c, ST_KIND_POWER);
    p->state = S_POWER;
}

/* FORWARD: the next current pulse (reading k of the n at current k / n), or the end. */
static void next_pulse(st_core_t *c)
{
    st_proc_t *p = &c->p;
    if (p->k >= p->total) {
        st_finish(c, ST_OK);
        return;
    }
    hal_release();
    hal_heater_dac(p->dac[p->k / p->n]);
    hal_heater_pwm(p->period_ns, p->on_ns); /* starts with the on-phase */
    hal_cut(1);                             /* ... which the cut ends */
    hal_adc_on_phase();
    st_arm(c, ST_KIND_FORWARD);
    p->state = S_PULSE;
}

/* Advance the procedure's run time. Polls come at least every ST_STATUS_MS, so the unsigned
 * difference never wraps; the total counts milliseconds (49 days) and never wraps with the
 * microsecond clock (71.6 min). */
static void advance(st_proc_t *p, uint32_t now)
{
    p->run_us += now - p->t_clock;
    p->t_clock = now;
    p->run_ms += p->run_us / 1000U;
    p->run_us %= 1000U;
}

static void step(st_core_t *c)
{
    st_proc_t *p = &c->p;
    uint32_t now = hal_now_us();
    if (p->state == S_IDLE) {
        return;
    }
    advance(p, now);
    if (p->state == S_SETTLE || p->state == S_GAP || p->state == S_CAL || p->state == S_CURVE ||
        p->state == S_SCAN) {
        /* (S_PULSE lasts a few milliseconds at most: no heartbeat) */
        if (due(now, p->t_status)) {
            send_status(c);
            p->t_status = now + ST_STATUS_MS * 1000U;
        }
    }
    switch (p->state) {
    case S_SETTLE:
        if (p->adc_armed) {
            if (!p->adc_ready) break;
            p->adc_armed = 0;
            regulate(c);
        }
        if (p->run_ms >= p->settle_ms) {
            if (p->proc == ST_PROC_FORWARD) {
                p->k = 0;
                next_pulse(c);
            } else if (p->proc == ST_PROC_CAL) {
                p->state = S_CAL;
                p->k = 0;
                hal_adc_at(now);
                p->adc_t_us = now;
                st_arm(c, ST_KIND_CAL);
            } else {
                p->k = 0;
                next_reading(c, now);
            }
        } else if (due(now, p->t_next)) {
            p->t_next = now + ST_CONTROL_TICK_MS * 1000U;
            if (!on_fixture(p)) {
                hal_adc_on_phase();
                st_arm(c, ST_KIND_POWER);
            }
        }
        break;
    case S_POWER:
        if (!p->adc_ready) break;
        p->adc_armed = 0;
        regulate(c);
        st_record(c, ST_KIND_POWER, 0);
        hal_cut(1);
        hal_adc_after_cut(p->window_us);
        st_arm(c, ST_KIND_STEADY);
        p->state = S_WINDOW;
        break;
    case S_WINDOW:
        if (!p->adc_ready) break;
        p->adc_armed = 0;
        st_record(c, ST_KIND_STEADY, p->window_us);
        if (p->proc == ST_PROC_COUPLING && p->ports > 1) { /* the other ports in the window */
            st_array_scan(c, now, 1, ST_KIND_STEADY, p->window_us, SCAN_STEADY);
            break;
        }
        hal_release();
        p->k++;
        p->t_next = now + (uint32_t)(p->interval_ms ? p->interval_ms : 100u) * 1000U;
        p->state = S_GAP;
        break;
    case S_GAP:
        if (!due(now, p->t_next)) break;
        if (p->proc == ST_PROC_FORWARD) {
            next_pulse(c);
        } else {
            next_reading(c, now);
        }
        break;
    case S_PULSE:
        if (!p->adc_ready) break;
        p->adc_armed = 0;
        st_record(c, ST_KIND_FORWARD, p->window_us / 2u);
        st_heater_off();
        p->k++;
        p->t_next = now + (uint32_t)p->interval_ms * 1000U;
        p->state = S_GAP;
        break;
    case S_CURVE:
        if (!p->adc_ready) break;
        p->adc_armed = 0;
        st_record(c, ST_KIND_CURVE, st_log_time_us(p->t_first_us, p->per_decade, p->k));
        if (p->proc == ST_PROC_COUPLING && p->ports > 1) { /* the other ports of this time */
            uint32_t t = st_log_time_us(p->t_first_us, p->per_decade, p->k);
            st_array_scan(c, p->t_cut + t, 1, ST_KIND_CURVE, t, SCAN_CURVE);
            break;
        }
        p->k++;
        st_curve_next(c, 0);
        break;
    case S_SCAN:
        st_array_step(c, now);
        break;
    case S_CAL:
        if (!p->adc_ready) break;
        p->adc_armed = 0;
        st_record(c, ST_KIND_CAL, (uint32_t)elapsed(p->adc_t_us, p->t_start));
        p->k++;
        if (p->k >= p->n) {
            st_finish(c, ST_OK);
            break;
        }
        p->adc_t_us = p->adc_t_us + (uint32_t)p->interval_ms * 1000U;
        hal_adc_at(p->adc_t_us);
        st_arm(c, ST_KIND_CAL);
        break;
    default:
        break;
    }
}

/* ------------------------------------------------------------------ entry points */
void st_core_init(st_core_t *c)
{
    memset(c, 0, sizeof *c);
    st_rx_init(&c->rx);
    st_ring_init(&c->ring);
}

uint8_t st_core_busy(const st_core_t *c)
{
    return c->p.state != S_IDLE || c->p.proc != ST_PROC_NONE;
}

void st_core_rx_byte(st_core_t *c, uint8_t byte)
{
    st_frame_t f;
    if (st_rx_feed(&c->rx, byte, &f)) {
        handle(c, &f);
    }
}

void st_core_adc_done(st_core_t *c, const uint16_t code[ST_NCH])
{
    if (c->p.adc_armed) {
        memcpy(c->p.codes, code, sizeof c->p.codes);
        c->p.adc_ready = 1;
    }
}

void st_core_poll(st_core_t *c)
{
    uint8_t was = c->p.state;
    if (c->ack_pending && st_ring_push(&c->ring, ST_MSG_ACK, c->ack, 4) == 0) {
        c->ack_pending = 0;
    }
    step(c);
    /* a step may complete immediately-available work; run until it settles */
    while (c->p.state != S_IDLE && c->p.state != was && !c->p.adc_armed) {
        was = c->p.state;
        step(c);
    }
    drain_fifo(c);
    if (c->p.proc != ST_PROC_NONE && c->p.state == S_IDLE && c->f_count == 0 &&
        !c->ack_pending && ring_free(c) > 0) {
        send_done(c);
        c->p.proc = ST_PROC_NONE;
    }
    flush_wire(c);
    if (c->p.state != S_IDLE) {
        uint32_t now = hal_now_us();
        uint32_t w = c->p.t_status;
        if (c->p.state == S_POWER || c->p.state == S_WINDOW || c->p.state == S_SCAN ||
            c->p.state == S_PULSE) {
            /* waiting for the ADC interrupt, no heartbeat in these states: a stale t_status
             * would make the core busy-poll (and froze the simulator at a float tie) */
            w = now + ST_STATUS_MS * 1000U;
        }
        if ((c->p.state == S_SETTLE || c->p.state == S_GAP) && !c->p.adc_armed &&
            elapsed(c->p.t_next, w) < 0) {
            w = c->p.t_next;
        }
        if (c->p.state == S_SETTLE && !c->p.adc_armed &&
            c->p.settle_ms - c->p.run_ms < ST_STATUS_MS) {
            /* settling ends before the next heartbeat: wake for it */
            uint32_t end = c->p.t_clock + (c->p.settle_ms - c->p.run_ms) * 1000U - c->p.run_us;
            if (elapsed(end, w) < 0) w = end;
        }
        if (elapsed(w, now) < 0) w = now;
        hal_wake_at(w);
    }
}
