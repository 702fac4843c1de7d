/* PIC18F4431 hardware layer (XC8). Fosc = 32 MHz (8 MHz crystal, 4x PLL), Fcy = 8 MHz.
 *
 * - Timer1 (1:8) counts microseconds; its overflow interrupt extends it to 32 bits.
 * - Power-control PWM module, generator 0 (PWM0/1): heater switch S; generator 1 (PDC1):
 *   heater current-source setpoint (RC-filtered); generator 2 (PDC2): calibration fixture
 *   setpoint. Output override (OVDCOND) cuts the heater; the PWM time-base interrupt
 *   synchronises a cut to the end of an on-phase.
 * - High-speed ADC in multi-channel sequential mode, 4 sample-and-holds + AN4, triggered by
 *   the Timer5 special event (scheduled instants and sample windows).
 * - EUSART at 115200 baud, interrupt-driven 64-byte transmit queue.
 * - Array board: RD0..RD2 address the heater demultiplexer (the current source to one of 8
 *   heaters), RD4..RD6 the TSP multiplexer (one of 8 diodes to the INA112); this board has
 *   one heater, so it reports 0 ports and the selects only set the (unconnected) pins.
 *
 * The same core (src/) runs on the host with hal/host; `make test` syntax-checks this file
 * against pic18f4431_regs.h (-DHOST_CHECK_PIC) since no PIC compiler is available in CI. */
#ifdef HOST_CHECK_PIC
#include "pic18f4431_regs.h"
#else
#include <xc.h>
#endif
#include "st_core.h"
#include "st_hal.h"

#define FCY_HZ 8000000UL
#define TX_QUEUE 64u

static st_core_t core;
static volatile uint16_t t1_high;            /* Timer1 overflow count */
static volatile uint8_t txq[TX_QUEUE];
static volatile uint8_t tx_head, tx_count;
static volatile uint8_t cut_pending;         /* cut at the next duty match */
static volatile uint8_t cut_active;          /* output overridden off since cut_time */
static volatile uint32_t cut_time;
static volatile uint32_t cut_delay_us;       /* ADC trigger delay after the cut (0: none) */
static volatile uint8_t adc_on_phase;
static uint32_t pwm_period_ns, pwm_on_ns;
static uint8_t pwm_prescale;                 /* PTCKPS: 0,1,2,3 -> 1,4,16,64 */

/* Board constants (INA112 gain 50 with 100 mV offset, 1 ohm x 10 current sense,
 * thermocouple amplifiers 100 mV/K (reference, 0..50 degC) and 50 mV/K (aux, -10..90 degC). */
static const st_board_t board = {
    {{-78125L, 1600000L, 800L},   /* TSP: uV at the INA input, Vd - Vref */
     {78125L, 0L, 16L},           /* Vd: uV */
     {78125L, 0L, 160L},          /* Id: uA */
     {78125L, 0L, 1600L},         /* Tamb: m degC */
     {78125L, -8000000L, 800L}},  /* Taux: m degC */
    250000UL, 1023u, 700000UL, -10000L, 90000L, 0u, 10u, "pic18f4431",
    1000UL, 0u, 0u}; /* block B's sense current: 1 mA; one heater (no array) */

const st_board_t *hal_board(void) { return &board; }

uint32_t hal_now_us(void)
{
    uint16_t hi, lo;
    do {
        hi = t1_high;
        lo = (uint16_t)TMR1L;
        lo |= (uint16_t)TMR1H << 8;
    } while (hi != t1_high);
    return ((uint32_t)hi << 16) | lo;
}

static uint32_t wake_us;
void hal_wake_at(uint32_t t_us) { wake_us = t_us; }

static void timer5_arm(uint32_t t_us)
{
    /* Timer5 counts Fcy/8 = 1 us ticks; long delays are split by the ISR */
    uint32_t d = t_us - hal_now_us();
    if ((int32_t)d < 2) {
        d = 2;
    }
    if (d > 0xFFFFUL) {
        d = 0xFFFFUL;
    }
    PR5H = (uint8_t)(d >> 8);
    PR5L = (uint8_t)d;
    TMR5H = 0;
    TMR5L = 0;
    PIR3bits.TMR5IF = 0;
    T5CON = 0x19; /* 1:8, special event reset and ADC trigger enabled, on */
}

static uint32_t adc_at_us;
static volatile uint8_t adc_armed;
void hal_adc_at(uint32_t t_us)
{
    adc_at_us = t_us;
    adc_armed = 1;
    timer5_arm(t_us);
}

void hal_adc_after_cut(uint32_t delay_us)
{
    if (delay_us == 0) {
        delay_us = 1;
    }
    di();
    if (cut_active) {
        ei();
        hal_adc_at(cut_time + delay_us); /* the cut has happened already */
        return;
    }
    cut_delay_us = delay_us; /* the ISR arms the conversion when the cut happens */
    ei();
}
void hal_adc_on_phase(void) { adc_on_phase = 1; }

void hal_heater_dac(uint16_t code)
{
    /* generator 1 duty: 10-bit code to the 14-bit duty register */
    uint16_t duty = (uint16_t)(code << 2);
    PDC1L = (uint8_t)duty;
    PDC1H = (uint8_t)(duty >> 8);
}

void hal_select_heater(uint8_t port) { LATD = (uint8_t)((LATD & 0xF8u) | (port & 0x07u)); }
void hal_select_tsp(uint8_t port) { LATD = (uint8_t)((LATD & 0x8Fu) | ((port & 0x07u) << 4)); }

void hal_fixture_dac(uint16_t code)
{
    uint16_t duty = (uint16_t)(code << 2);
    PDC2L = (uint8_t)duty;
    PDC2H = (uint8_t)(duty >> 8);
}

void hal_heater_pwm(uint32_t period_ns, uint32_t on_ns)
{
    /* edge-aligned: period = (PTPER + 1) * prescale / Fcy; duty resolution Tcy / 4 */
    uint32_t ticks = period_ns / 125UL;
    uint32_t duty;
    pwm_period_ns = period_ns;
    pwm_on_ns = on_ns;
    PTCON1 = 0x00; /* time base off */
    cut_pending = 0;
    cut_active = 0;
    if (period_ns == 0 || on_ns == 0) {
        OVDCONS = 0x00;
        OVDCOND = 0x00; /* all outputs overridden to inactive */
        return;
    }
    pwm_prescale = 0;
    while (ticks > 4096UL && pwm_prescale < 3u) {
        ticks >>= 2;
        pwm_prescale++;
    }
    if (ticks > 4096UL) {
        ticks = 4096UL;
    }
    PTPERL = (uint8_t)(ticks - 1UL);
    PTPERH = (uint8_t)((ticks - 1UL) >> 8);
    duty = on_ns >= period_ns ? (ticks << 2) : (uint32_t)(((uint32_t)(on_ns / 125UL) << 2) >> (2u * pwm_prescale));
    PDC0L = (uint8_t)duty;
    PDC0H = (uint8_t)(duty >> 8);
    /* special event trigger in the middle of the on-phase (for on-phase readings) */
    SEVTCMPL = (uint8_t)((duty >> 3));
    SEVTCMPH = (uint8_t)((duty >> 11));
    PTCON0 = (uint8_t)(pwm_prescale << 2); /* free-running edge-aligned */
    OVDCOND = 0xFF;                        /* outputs follow the PWM */
    PTCON1 = 0x80;                         /* time base on */
}

void hal_cut(uint8_t at_on_end)
{
    if (at_on_end && pwm_on_ns < pwm_period_ns) {
        cut_pending = 1; /* the PTIF / duty-match interrupt overrides at the on-phase end */
    } else {
        OVDCONS = 0x00;
        OVDCOND = 0x00;
        cut_time = hal_now_us();
        cut_active = 1;
        if (cut_delay_us) {
            hal_adc_at(cut_time + cut_delay_us);
            cut_delay_us = 0;
        }
    }
}

void hal_release(void)
{
    cut_pending = 0;
    cut_active = 0;
    cut_delay_us = 0;
    OVDCOND = 0xFF;
}

uint16_t hal_uart_space(void) { return (uint16_t)(TX_QUEUE - tx_count); }

void hal_uart_write(const uint8_t *buf, uint16_t n)
{
    uint16_t i;
    for (i = 0; i < n && tx_count < TX_QUEUE; i++) {
        di();
        txq[(uint8_t)((tx_head + tx_count) % TX_QUEUE)] = buf[i];
        tx_count++;
        ei();
    }
    PIE1 |= 0x10; /* TXIE */
}

static void adc_read_all(void)
{
    uint16_t code[ST_NCH];
    uint8_t i;
    /* the sequencer has converted AN0..AN3 (simultaneous S/H) and AN4; results come out of
     * the 4-deep ADRES FIFO in channel order */
    for (i = 0; i < ST_NCH; i++) {
        code[i] = (uint16_t)(((uint16_t)ADRESH << 8) | ADRESL) & 0x03FFu;
    }
    st_core_adc_done(&core, code);
}

void __interrupt(high_priority) isr_high(void)
{
    if (PIR1bits.TMR1IF) {
        PIR1bits.TMR1IF = 0;
        t1_high++;
    }
    if (PIR3bits.PTIF) { /* PWM time base: duty match of the on-phase end */
        PIR3bits.PTIF = 0;
        if (cut_pending) {
            OVDCONS = 0x00;
            OVDCOND = 0x00;
            cut_pending = 0;
            cut_time = hal_now_us();
            cut_active = 1;
            if (cut_delay_us) {
                hal_adc_at(cut_time + cut_delay_us);
                cut_delay_us = 0;
            }
        }
        if (adc_on_phase) {
            adc_on_phase = 0;
            ADCON0bits.GO_DONE = 1;
            adc_armed = 1;
        }
    }
    if (PIR3bits.TMR5IF) {
        PIR3bits.TMR5IF = 0;
        if (adc_armed && (int32_t)(hal_now_us() - adc_at_us) < -2) {
            timer5_arm(adc_at_us); /* long delay: rearm */
        }
    }
    if (PIR1bits.ADIF) {
        PIR1bits.ADIF = 0;
        adc_armed = 0;
        adc_read_all();
    }
}

void __interrupt(low_priority) isr_low(void)
{
    if (PIR1bits.RCIF) {
        if (RCSTAbits.OERR) {
            RCSTAbits.CREN = 0;
            RCSTAbits.CREN = 1;
        }
        st_core_rx_byte(&core, RCREG);
    }
    if (PIR1bits.TXIF && tx_count) {
        TXREG = txq[tx_head];
        tx_head = (uint8_t)((tx_head + 1u) % TX_QUEUE);
        tx_count--;
        if (tx_count == 0) {
            PIE1 &= (uint8_t)~0x10u;
        }
    }
}

static void hw_init(void)
{
    OSCCON = 0x70;
    ANSEL0 = 0x1F; /* AN0..AN4 analog */
    TRISA = 0x1F;
    TRISB = 0x00;  /* PWM outputs */
    TRISC = 0x80;  /* RX in, TX out */
    TRISD = 0x00;  /* multiplexer addresses (array board) */
    T1CON = 0xB1;  /* 16-bit, 1:8, on */
    ADCON0 = 0x1D; /* continuous off, multi-channel sequential (SEQM2), on */
    ADCON1 = 0x10; /* AVdd/AVss reference, FIFO enabled */
    ADCON2 = 0xA2; /* right justified, 4 Tad acquisition, Fosc/32 */
    ADCON3 = 0x80; /* trigger from the Timer5 / PWM special event */
    ADCHS = 0x00;
    TXSTA = 0x24;  /* 8-bit, async, high speed */
    RCSTA = 0x90;
    BAUDCON = 0x08;
    SPBRGH = 0;
    SPBRG = 68; /* 32 MHz / (4 (68 + 1)) = 115942 baud */
    PIE1 = 0x61;   /* ADIE, RCIE, TMR1IE */
    PIE3 = 0x11;   /* PTIE, TMR5IE */
    RCON = 0x80;   /* interrupt priorities */
    INTCON = 0xC0;
    hal_heater_pwm(0, 0);
}

void main(void)
{
    hw_init();
    st_core_init(&core);
    for (;;) {
        CLRWDT();
        st_core_poll(&core);
        (void)wake_us; /* the main loop polls continuously; wake_us serves the host build */
    }
}
