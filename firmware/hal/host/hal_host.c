#include <stdlib.h>
#include <string.h>
#include "hal_host.h"

static hh_device_t *cur; /* the device whose core is running (single-threaded driver) */

static void op(uint32_t code, uint32_t a, uint32_t b)
{
    hh_state_t *s = &cur->s;
    if (s->n_ops >= HH_MAX_OPS) {
        s->ops_lost++;
        return;
    }
    s->ops[s->n_ops].op = code;
    s->ops[s->n_ops].a = a;
    s->ops[s->n_ops].b = b;
    s->ops[s->n_ops].t_us = s->now_us;
    s->n_ops++;
}

const st_board_t *hal_board(void) { return &cur->s.board; }
uint32_t hal_now_us(void) { return cur->s.now_us; }
void hal_wake_at(uint32_t t_us) { cur->s.wake_us = t_us; cur->s.wake_set = 1; }
void hal_heater_dac(uint16_t code) { op(HH_OP_DAC, code, 0); }
void hal_heater_pwm(uint32_t period_ns, uint32_t on_ns) { op(HH_OP_PWM, period_ns, on_ns); }
void hal_cut(uint8_t at_on_end) { op(HH_OP_CUT, at_on_end, 0); }
void hal_release(void) { op(HH_OP_RELEASE, 0, 0); }
void hal_adc_at(uint32_t t_us) { op(HH_OP_ADC_AT, t_us, 0); }
void hal_adc_after_cut(uint32_t delay_us) { op(HH_OP_ADC_AFTER_CUT, delay_us, 0); }
void hal_adc_on_phase(void) { op(HH_OP_ADC_ON_PHASE, 0, 0); }
void hal_fixture_dac(uint16_t code) { op(HH_OP_FIXTURE, code, 0); }
void hal_select_heater(uint8_t port) { op(HH_OP_HEATER, port, 0); }
void hal_select_tsp(uint8_t port) { op(HH_OP_TSP, port, 0); }
uint16_t hal_uart_space(void)
{
    uint32_t free = HH_TX_LEN - cur->s.tx_len;
    return free > 0xFFFFu ? 0xFFFFu : (uint16_t)free;
}
void hal_uart_write(const uint8_t *buf, uint16_t n)
{
    hh_state_t *s = &cur->s;
    if (n > HH_TX_LEN - s->tx_len) {
        n = (uint16_t)(HH_TX_LEN - s->tx_len);
    }
    memcpy(s->tx + s->tx_len, buf, n);
    s->tx_len += n;
}

hh_device_t *hh_new(void)
{
    hh_device_t *d = (hh_device_t *)calloc(1, sizeof *d);
    return d;
}

void hh_free(hh_device_t *d) { free(d); }

void hh_init(hh_device_t *d)
{
    cur = d;
    st_core_init(&d->core);
}

void hh_rx(hh_device_t *d, const uint8_t *buf, uint32_t n)
{
    uint32_t i;
    cur = d;
    for (i = 0; i < n; i++) {
        st_core_rx_byte(&d->core, buf[i]);
    }
}

void hh_adc(hh_device_t *d, const uint16_t *code)
{
    cur = d;
    st_core_adc_done(&d->core, code);
}

void hh_poll(hh_device_t *d)
{
    cur = d;
    d->s.wake_set = 0;
    st_core_poll(&d->core);
}

uint32_t hh_busy(hh_device_t *d) { return st_core_busy(&d->core); }

uint32_t hh_blocked(hh_device_t *d)
{
    const st_ring_t *r = &d->core.ring;
    uint16_t used = (uint16_t)(r->next_seq - r->acked);
    return d->core.f_count > 0 && used + 3u >= ST_RING_FRAMES;
}

void hh_set_version(uint8_t major, uint8_t minor, uint8_t patch)
{
    st_fw_version[0] = major;
    st_fw_version[1] = minor;
    st_fw_version[2] = patch;
}
