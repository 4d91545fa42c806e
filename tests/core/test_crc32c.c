/*
 * core/crc32c.h: CRC-32C against the check value of the CRC catalogue
 * ("123456789" -> 0xE3069283), RFC 3720's iSCSI test vectors (B.4: 32
 * zeros, 32 ones, 0..31, 31..0), and a bytewise bit-by-bit reference over
 * random lengths, alignments and splits (the slicing-by-eight path, its
 * tail, and continuing from a previous value).
 */
#include "testutil.h"

#include <stdint.h>
#include <string.h>

#include "core/crc32c.h"

/* The reflected polynomial one bit at a time: the definition. */
static uint32_t
crc_bitwise(const unsigned char *p, size_t n) {
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++)
            c = c & 1 ? (c >> 1) ^ 0x82F63B78u : c >> 1;
    }
    return ~c;
}

static void
test_known_values(void **state) {
    (void)state;
    assert_int_equal(vv_crc32c(0, "123456789", 9), 0xE3069283u);
    assert_int_equal(vv_crc32c(0, "", 0), 0);
    unsigned char b[32];
    memset(b, 0, sizeof b);
    assert_int_equal(vv_crc32c(0, b, 32), 0x8A9136AAu);
    memset(b, 0xFF, sizeof b);
    assert_int_equal(vv_crc32c(0, b, 32), 0x62A8AB43u);
    for (int i = 0; i < 32; i++)
        b[i] = (unsigned char)i;
    assert_int_equal(vv_crc32c(0, b, 32), 0x46DD794Eu);
    for (int i = 0; i < 32; i++)
        b[i] = (unsigned char)(31 - i);
    assert_int_equal(vv_crc32c(0, b, 32), 0x113FDB5Cu);
}

static void
test_against_bitwise(void **state) {
    (void)state;
    unsigned char buf[4096 + 16];
    uint64_t s = 78;
    for (size_t i = 0; i < sizeof buf; i++)
        buf[i] = (unsigned char)vt_rnd(&s, 0, 256);
    for (int t = 0; t < 300; t++) {
        const size_t off = (size_t)vt_rnd(&s, 0, 16), n = (size_t)vt_rnd(&s, 0, 4096);
        const uint32_t want = crc_bitwise(buf + off, n);
        assert_int_equal(vv_crc32c(0, buf + off, n), want);
        const size_t cut = n ? (size_t)vt_rnd(&s, 0, (double)n) : 0;
        assert_int_equal(vv_crc32c(vv_crc32c(0, buf + off, cut), buf + off + cut, n - cut), want);
    }
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_known_values),
        cmocka_unit_test(test_against_bitwise),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
