//! The JSON Lines reader's fast scanner against serde_json: on records as pacs writes them, on
//! every number literal JSON (and not JSON) can spell near the edges of f64, and on thousands of
//! random edits of records, every line the scanner takes is one serde_json takes, with the same
//! values bit for bit (`fast_path_agrees`); lines it does not take go to serde_json unchanged.

use pacs_log::jsonl::{fast_path_agrees, fast_path_takes};

const RECORDS: &[&str] = &[
    "{\"type\":\"robot\",\"t\":0.001,\"q\":[0.012002984195271257,-0.7848432820745567,-0.0005283976453661861,-2.352341624880035,-0.013630849591725966,1.561103065746978,0.77970376188577],\"dq\":[-7.061073045433511e-5,2.9805773898642442e-5,0.0,0,-0,1e-300,5e-324],\"ddq\":[-0.14122146090867022,0.059611547797284885,0.04419561259462412,1,2,3,4]}\n",
    "{\"binding\":{\"kind\":\"none\"},\"contact_energy\":0.0,\"contact_threshold\":0.0,\"min_separation\":0.5609422284033653,\"on_failsafe\":false,\"path_speed\":1.0,\"t\":0.001,\"type\":\"shield\",\"verified\":true}\n",
    "{\"type\":\"human\",\"t\":0.0,\"t_meas\":0.0,\"id\":\"human0\",\"positions\":[[2.3571958824156165,-0.02747683684835855,0.6496117574809898],[2.343778997716555,0.018146379965176027,0.4018017933438838]]}\n",
    "{\"type\":\"object\",\"t\":0.0,\"t_meas\":0.0,\"id\":\"sphere-b\",\"position\":[0.47393131955634177,-0.380406300279194,0.04728062528461232],\"velocity\":[-0.0029595973326424756,0.0785904491975051,-0.012240240762220795]}\n",
    "{\"type\":\"event\",\"t\":7.949,\"name\":\"end\"}\n",
    "  { \"type\" : \"robot\" , \"t\" : 1E+2 , \"q\" : [ 1 , 2.5e-3 ] }  \r\n",
    "{\"type\":\"shield\",\"t\":1,\"x\":[{\"a\":[null,true,false,\"s\",{}]},[]],\"y\":{}}\n",
    "{\"type\":\"robot\",\"t\":1,\"t\":2,\"q\":[]}\n",
    "{}\n",
];

const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "0.0",
    "-0.0",
    "1",
    "-1",
    "01",
    "-01",
    "1.",
    ".5",
    "+1",
    "1e5",
    "1E5",
    "1e+5",
    "1e-5",
    "1e",
    "1e+",
    "-",
    "1.5e400",
    "1e400",
    "-1e400",
    "1e-400",
    "-1e-400",
    "1.7976931348623157e308",
    "1.7976931348623158e308",
    "1.7976931348623159e308",
    "2.2250738585072011e-308",
    "2.2250738585072014e-308",
    "4.9e-324",
    "2.4703282292062327e-324",
    "2.4703282292062328e-324",
    "9007199254740993",
    "-9007199254740993",
    "9223372036854775807",
    "-9223372036854775808",
    "-9223372036854775809",
    "18446744073709551615",
    "18446744073709551616",
    "123456789012345678901234567890",
    "0.30000000000000004",
    "0.1000000000000000055511151231257827",
    "3.141592653589793238462643383279",
    "NaN",
    "Infinity",
    "-Infinity",
    "1_0",
    "0x10",
    "1.0e00000000000000000001",
    "0e0",
    "-0e-0",
    "00",
    "1e-0",
    // Around the bound below which a skipped number is taken without converting it.
    "1e300",
    "1e308",
    "1e309",
    "12e307",
    "99e307",
    "0.001e310",
    "0000000000000000000001e308",
    "-1e308",
    "1e-2000",
    "1e99999999999999999999",
    "1e-99999999999999999999",
];

/// xorshift64*.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

#[test]
fn records_as_pacs_writes_them_take_the_fast_path_and_agree() {
    for r in RECORDS {
        assert!(fast_path_agrees(r), "{r}");
    }
    // The common records are taken (else the scanner would only cost time).
    for r in &RECORDS[..6] {
        assert!(fast_path_takes(r), "{r}");
    }
}

#[test]
fn every_number_literal_agrees_wherever_it_stands() {
    let mut taken = 0;
    for n in NUMBERS {
        for line in [
            format!("{{\"type\":\"robot\",\"t\":{n},\"q\":[{n},{n}]}}\n"),
            format!("{{\"type\":\"human\",\"t\":0,\"positions\":[[{n},0,{n}]]}}\n"),
            format!("{{\"type\":\"shield\",\"t\":0,\"other\":[{n},{{\"k\":{n}}}]}}\n"),
        ] {
            assert!(fast_path_agrees(&line), "{line}");
            taken += fast_path_takes(&line) as usize;
        }
    }
    assert!(taken > 60, "{taken}");
}

/// The scanner reads digits a word of eight bytes at a time (converted or, in skipped fields,
/// only checked) and skips whitespace with a one-byte test first: every run length (0–24
/// digits, 0–20 string bytes) at every offset of the line (0–8 spaces in front) with every kind
/// of byte after the run, so that each byte of the run and the byte after it fall on each
/// position of a word and past the last whole word of the line.
#[test]
fn digit_runs_and_strings_agree_at_every_word_offset() {
    let mut taken = 0;
    let mut lines = 0;
    for pad in 0..=8 {
        let sp = " ".repeat(pad);
        for len in 0..=24 {
            let run: String = (0..len).map(|k| char::from(b'1' + (k % 9) as u8)).collect();
            for (int, frac, tail) in [
                (run.as_str(), "", ""),
                ("0", run.as_str(), ""),
                (run.as_str(), run.as_str(), ""),
                (run.as_str(), "5", "e-3"),
                ("7", run.as_str(), "E+12"),
                ("-0", run.as_str(), ""),
            ] {
                let n = if frac.is_empty() {
                    format!("{int}{tail}")
                } else {
                    format!("{int}.{frac}{tail}")
                };
                for after in ["", " ", "x", "é", "/"] {
                    for line in [
                        format!(
                            "{sp}{{\"type\":\"robot\",\"t\":{n}{after},\"q\":[{n},{n}{after}]}}\n"
                        ),
                        format!("{{\"type\":\"shield\",\"t\":0,\"skip\":[{sp}{n}{after}]}}{sp}\n"),
                        format!("{{\"t\":0,\"type\":\"robot\",\"q\":[{sp}{n}]{after}}}"),
                    ] {
                        assert!(fast_path_agrees(&line), "{line:?}");
                        taken += fast_path_takes(&line) as usize;
                        lines += 1;
                    }
                }
            }
        }
        for len in 0..=20 {
            let body: String = (0..len)
                .map(|k| char::from(b'a' + (k % 26) as u8))
                .collect();
            for stop in [
                "", "\\\"", "\\n", "\\u0041", "\u{1}", "\t", "\u{7f}", "é", "\u{1f}", " ",
            ] {
                for line in [
                    format!("{sp}{{\"type\":\"event\",\"t\":1,\"name\":\"{body}{stop}{body}\"}}\n"),
                    format!(
                        "{{\"type\":\"shield\",\"{sp}{body}{stop}\":\"{body}{stop}\",\"t\":2}}"
                    ),
                    format!("{{\"type\":\"human\",\"t\":0,\"id\":\"{body}{stop}\"}}"),
                ] {
                    assert!(fast_path_agrees(&line), "{line:?}");
                    taken += fast_path_takes(&line) as usize;
                    lines += 1;
                }
            }
        }
    }
    // Most of the lines are JSON the scanner takes (numbers of at most 19 digits and plain
    // strings): the word-at-a-time paths are exercised, not only serde_json's.
    assert!(taken * 3 > lines, "{taken} of {lines}");
}

#[test]
fn random_edits_of_records_agree() {
    let alphabet: &[u8] = b"{}[],:.-+eE0123456789 \t\r\n\\\"uxntf/\x01";
    let mut rng = Rng(0x5EED_1234_ABCD_0001);
    let (mut taken, cases) = (0usize, 40_000);
    for _ in 0..cases {
        let mut line: Vec<u8> = RECORDS[rng.below(RECORDS.len())].as_bytes().to_vec();
        for _ in 0..1 + rng.below(3) {
            let at = rng.below(line.len() + 1);
            match rng.below(4) {
                0 if at < line.len() => {
                    line.remove(at);
                }
                1 => line.insert(at, alphabet[rng.below(alphabet.len())]),
                2 if at < line.len() => line[at] = alphabet[rng.below(alphabet.len())],
                _ => {
                    let n = NUMBERS[rng.below(NUMBERS.len())];
                    let at = at.min(line.len());
                    line.splice(at..at, n.bytes());
                }
            }
        }
        let Ok(text) = String::from_utf8(line) else {
            continue;
        };
        assert!(fast_path_agrees(&text), "{text:?}");
        taken += fast_path_takes(&text) as usize;
    }
    // Many edits keep a valid record (a digit changed, whitespace added): those reach the
    // comparison.
    assert!(taken > cases / 10, "{taken} of {cases}");
}

/// Numbers as writers print them (shortest round trip, scientific, fixed with fewer digits, long
/// decimal expansions): the scanner's value is the correctly rounded one (the standard library's
/// parse), bit for bit, and serde_json agrees: 100,000 random doubles, each in four spellings.
#[test]
fn random_doubles_read_correctly_rounded() {
    let mut rng = Rng(0xD0B1_E5EE_D000_0002);
    for _ in 0..100_000 {
        let bits = rng.next();
        // Half over every finite double, half over magnitudes near what logs hold (1e-6..1e3).
        let x = if bits & 1 == 0 {
            f64::from_bits(rng.next())
        } else {
            let u = (rng.next() >> 11) as f64 / (1u64 << 53) as f64;
            let sign = if bits & 2 == 0 { 1.0 } else { -1.0 };
            sign * 10f64.powf(-6.0 + 9.0 * u)
        };
        if !x.is_finite() {
            continue;
        }
        let digits = 1 + rng.below(20);
        for text in [
            format!("{x}"),
            format!("{x:e}"),
            format!("{x:.digits$e}"),
            format!("{x:.digits$}"),
        ] {
            let line = format!("{{\"type\":\"robot\",\"t\":0,\"q\":[{text}]}}\n");
            assert!(fast_path_agrees(&line), "{line}");
            let want: f64 = text.parse().unwrap();
            if want.is_finite() && fast_path_takes(&line) {
                let got = pacs_log::jsonl::fast_path_value(&text);
                assert_eq!(got.map(f64::to_bits), Some(want.to_bits()), "{text}");
            }
        }
    }
}

/// The scanner's exact fast path (a mantissa of at most 2⁵³ with a decimal exponent within ±22,
/// one IEEE multiplication or division) and the numbers just outside it (2⁵³ + 1, 19 and 20
/// significant digits, exponents ±23, leading and trailing zeros, exponent spellings): every
/// value is the standard library's correctly rounded parse, bit for bit. 200,000 random
/// literals around the boundaries.
#[test]
fn the_exact_fast_path_agrees_with_the_standard_parse() {
    let mut rng = Rng(0xFA57_9A7B_0000_0003);
    let edge_mantissas: [u64; 8] = [
        0,
        1,
        (1 << 53) - 1,
        1 << 53,
        (1 << 53) + 1,
        9_999_999_999_999_999_999,
        1_000_000_000_000_000_000,
        12_003_007_732_181_409,
    ];
    for case in 0..200_000 {
        let m: u64 = match case % 4 {
            0 => edge_mantissas[rng.below(edge_mantissas.len())],
            1 => rng.next() >> (11 + rng.below(50)),
            2 => rng.next() % 10_000_000_000_000_000_000,
            _ => (1 << 53) - 8 + rng.below(16) as u64,
        };
        let e = rng.below(51) as i64 - 25;
        let digits = m.to_string();
        // m·10^e spelled with the point moved (`e` fraction digits when negative), with
        // leading or trailing zeros, or with an exponent.
        let lead = "0".repeat(rng.below(3));
        let trail = "0".repeat(rng.below(3));
        let sign = if rng.below(2) == 0 { "" } else { "-" };
        let text = match rng.below(3) {
            0 if e < 0 => {
                let k = (-e) as usize;
                let padded = format!("{}{digits}", "0".repeat(k.saturating_sub(digits.len()) + 1));
                let (int, frac) = padded.split_at(padded.len() - k);
                let int = int.trim_start_matches('0');
                let int = if int.is_empty() { "0" } else { int };
                format!("{sign}{int}.{frac}{trail}")
            }
            0 if m == 0 => format!("{sign}0"),
            0 => format!("{sign}{digits}{}", "0".repeat(e as usize)),
            1 => format!("{sign}{digits}e{e}"),
            _ => format!(
                "{sign}0.{lead}{digits}E{}",
                e + digits.len() as i64 + lead.len() as i64
            ),
        };
        let want: f64 = text.parse().unwrap();
        let got = pacs_log::jsonl::fast_path_value(&text);
        assert_eq!(got.map(f64::to_bits), Some(want.to_bits()), "{text}");
    }
}

/// The wide-product conversion (16–19 significant digits, decimal exponents −60..60, where the
/// exact path does not apply; plus mantissas at powers of two and halfway-looking digit
/// patterns): every value the scanner returns is the standard library's correctly rounded
/// parse, bit for bit. 1,000,000 literals (`PACS_JSONL_CASES` for more).
#[test]
fn the_wide_product_agrees_with_the_standard_parse() {
    let cases: usize = std::env::var("PACS_JSONL_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_000_000);
    let mut rng = Rng(0x1DE5_9A7B_0000_0004);
    for case in 0..cases {
        let m: u64 = match case % 5 {
            0 => 1_000_000_000_000_000 + rng.next() % 9_000_000_000_000_000, // 16–19 digits
            1 => rng.next() % 10_000_000_000_000_000_000,
            2 => (1u64 << (54 + rng.below(10)))
                .wrapping_add(rng.below(3) as u64)
                .wrapping_sub(1),
            3 => {
                // A double's shortest digits, padded to 17–19 digits with 5s and 0s.
                let x = f64::from_bits(0x3F00_0000_0000_0000 + (rng.next() >> 12));
                let d = format!("{x:e}");
                let (mant, _) = d.split_once('e').unwrap();
                let mut digits: String = mant.chars().filter(char::is_ascii_digit).collect();
                digits.push(if rng.below(2) == 0 { '5' } else { '0' });
                while digits.len() < 17 {
                    digits.push('0');
                }
                digits.truncate(19);
                digits.parse().unwrap()
            }
            _ => rng.next() >> rng.below(12),
        };
        let e = rng.below(121) as i64 - 60;
        let sign = if rng.below(2) == 0 { "" } else { "-" };
        let text = format!("{sign}{m}e{e}");
        let want: f64 = text.parse().unwrap();
        if !want.is_finite() {
            continue;
        }
        let got = pacs_log::jsonl::fast_path_value(&text);
        assert_eq!(got.map(f64::to_bits), Some(want.to_bits()), "{text}");
    }
}
