#include "st_crc16.h"

uint16_t st_crc16_update(uint16_t crc, uint8_t byte)
{
    uint8_t i;
    crc ^= (uint16_t)((uint16_t)byte << 8);
    for (i = 0; i < 8; i++) {
        crc = (crc & 0x8000u) ? (uint16_t)((crc << 1) ^ 0x1021u) : (uint16_t)(crc << 1);
    }
    return crc;
}

uint16_t st_crc16(const uint8_t *data, size_t n)
{
    uint16_t crc = ST_CRC16_INIT;
    size_t i;
    for (i = 0; i < n; i++) {
        crc = st_crc16_update(crc, data[i]);
    }
    return crc;
}
