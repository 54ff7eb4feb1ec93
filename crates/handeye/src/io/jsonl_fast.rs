//! The fast path of the JSON Lines reader: a record of the common shape read straight from the
//! line, with no allocation and no `serde_json::Value`.
//!
//! The common shape is one object whose keys are among `stamp`, `base_from_gripper`,
//! `gripper_from_base`, `camera_from_target` and `target_from_camera`, each at most once (the
//! keys plain, without escapes), `stamp` a number or `null`, and each transform a bare 4×4 array
//! of numbers or an object of `matrix`, `translation` and `quaternion_xyzw` (SPEC sec. 7): what
//! `handeye simulate` writes and most recorders print. Anything else — another key, a string
//! where a number goes, a malformed line — makes [`scan`]
//! return `None`, and the line is read by the general path, which gives the same result or
//! names the problem (file, line, field). The fast path therefore never decides an error.
//!
//! Numbers are checked against JSON's grammar and converted in one pass by lexical-core's JSON
//! number format, correctly rounded: the same `f64` as serde_json's (built with `float_roundtrip`)
//! for every number JSON allows, integers and `-0` included. A number out of `f64`'s range is left
//! to the general path, which refuses it.

use nalgebra::Matrix4;

use crate::io::transform::TransformNumbers;

/// What a line of the common shape gives: the stamp and the numbers of the two transforms as
/// written, each with whether the file gives it in the other direction (`gripper_from_base`,
/// `target_from_camera`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Scanned {
    /// The stamp, seconds, when given and not `null`.
    pub stamp: Option<f64>,
    /// The robot's transform, and whether it is `gripper_from_base`.
    pub robot: (TransformNumbers, bool),
    /// The camera's transform, and whether it is `target_from_camera`.
    pub camera: (TransformNumbers, bool),
}

/// The keys of the common shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Key {
    Stamp,
    /// A robot pose, inverted when `true` (`gripper_from_base`).
    Robot(bool),
    /// A camera pose, inverted when `true` (`target_from_camera`).
    Camera(bool),
    /// The robot's joint angles, read by the general parser (`jsonl::parse_record`): passed over here
    /// when they are a list of numbers.
    Joints,
}

/// Reads `line` (a record's text, line end removed) when it has the common shape; `None`
/// otherwise, the general path to decide.
pub(crate) fn scan(line: &str) -> Option<Scanned> {
    let mut c = Cursor {
        bytes: line.as_bytes(),
        at: 0,
    };
    c.space();
    c.eat(b'{')?;
    let mut stamp: Option<Option<f64>> = None;
    let mut robot = None;
    let mut camera = None;
    let mut joints = false;
    loop {
        c.space();
        let key = c.key()?;
        c.space();
        c.eat(b':')?;
        c.space();
        match key {
            Key::Stamp if stamp.is_none() => stamp = Some(c.number_or_null()?),
            Key::Robot(inverted) if robot.is_none() => robot = Some((c.transform()?, inverted)),
            Key::Camera(inverted) if camera.is_none() => {
                camera = Some((c.transform()?, inverted));
            }
            Key::Joints if !joints => {
                c.number_list()?;
                joints = true;
            }
            // A key given twice (or both names of one pose): the general path says which.
            _ => return None,
        }
        c.space();
        match c.next()? {
            b',' => continue,
            b'}' => break,
            _ => return None,
        }
    }
    c.space();
    if c.at != line.len() {
        return None;
    }
    Some(Scanned {
        stamp: stamp.flatten(),
        robot: robot?,
        camera: camera?,
    })
}

/// A position in a line.
struct Cursor<'a> {
    /// The line's bytes.
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    /// The next byte, consumed.
    fn next(&mut self) -> Option<u8> {
        let b = *self.bytes.get(self.at)?;
        self.at += 1;
        Some(b)
    }

    /// Consumes `want`, or fails.
    fn eat(&mut self, want: u8) -> Option<()> {
        (self.next()? == want).then_some(())
    }

    /// Skips JSON's whitespace (space, tab, carriage return, line feed).
    fn space(&mut self) {
        while let Some(b' ' | b'\t' | b'\r' | b'\n') = self.bytes.get(self.at) {
            self.at += 1;
        }
    }

    /// A plain string (no escapes), its bytes.
    fn string(&mut self) -> Option<&'a [u8]> {
        self.eat(b'"')?;
        let (bytes, start) = (self.bytes, self.at);
        let length = bytes[start..].iter().position(|&b| b == b'"')?;
        self.at = start + length + 1;
        let text = &bytes[start..start + length];
        (!text.contains(&b'\\')).then_some(text)
    }

    /// A key of the common shape.
    fn key(&mut self) -> Option<Key> {
        match self.string()? {
            b"stamp" => Some(Key::Stamp),
            b"base_from_gripper" => Some(Key::Robot(false)),
            b"gripper_from_base" => Some(Key::Robot(true)),
            b"camera_from_target" => Some(Key::Camera(false)),
            b"target_from_camera" => Some(Key::Camera(true)),
            b"joints" => Some(Key::Joints),
            _ => None,
        }
    }

    /// A non-empty list of finite numbers, passed over.
    fn number_list(&mut self) -> Option<()> {
        self.eat(b'[')?;
        loop {
            self.space();
            self.number()?;
            self.space();
            match self.next()? {
                b',' => continue,
                b']' => return Some(()),
                _ => return None,
            }
        }
    }

    /// A number, or `null` (`None`).
    fn number_or_null(&mut self) -> Option<Option<f64>> {
        if self.bytes[self.at..].starts_with(b"null") {
            self.at += 4;
            return Some(None);
        }
        self.number().map(Some)
    }

    /// A finite number in JSON's grammar, `-? (0 | [1-9][0-9]*) (. [0-9]+)? ([eE] [+-]? [0-9]+)?`,
    /// checked and converted in one pass by lexical-core's JSON number format (correctly rounded,
    /// like the standard library's parser; the same `f64` as serde_json's, tested below). A
    /// number out of range comes out infinite and is left to the general path.
    fn number(&mut self) -> Option<f64> {
        if let Some((x, used)) = short_decimal(&self.bytes[self.at..]) {
            self.at += used;
            return Some(x);
        }
        const JSON: u128 = lexical_core::format::JSON;
        const OPTIONS: lexical_core::ParseFloatOptions = lexical_core::ParseFloatOptions::new();
        let rest = self.bytes.get(self.at..)?;
        let (x, used) =
            lexical_core::parse_partial_with_options::<f64, JSON>(rest, &OPTIONS).ok()?;
        self.at += used;
        x.is_finite().then_some(x)
    }

    /// A transform: a bare 4×4 array, or an object with `matrix`, `translation` and
    /// `quaternion_xyzw` (each at most once, no other key).
    fn transform(&mut self) -> Option<TransformNumbers> {
        if self.bytes.get(self.at) == Some(&b'[') {
            return Some(TransformNumbers {
                matrix: Some(self.matrix()?),
                ..TransformNumbers::default()
            });
        }
        self.eat(b'{')?;
        let mut numbers = TransformNumbers::default();
        loop {
            self.space();
            let key = self.string()?;
            self.space();
            self.eat(b':')?;
            self.space();
            match key {
                b"matrix" if numbers.matrix.is_none() => numbers.matrix = Some(self.matrix()?),
                b"translation" if numbers.translation.is_none() => {
                    numbers.translation = Some(self.numbers()?);
                }
                b"quaternion_xyzw" if numbers.quaternion_xyzw.is_none() => {
                    numbers.quaternion_xyzw = Some(self.numbers()?);
                }
                _ => return None,
            }
            self.space();
            match self.next()? {
                b',' => continue,
                b'}' => return Some(numbers),
                _ => return None,
            }
        }
    }

    /// An array of exactly N numbers.
    fn numbers<const N: usize>(&mut self) -> Option<[f64; N]> {
        let mut out = [0.0; N];
        self.eat(b'[')?;
        for (k, x) in out.iter_mut().enumerate() {
            self.space();
            *x = self.number()?;
            self.space();
            self.eat(if k + 1 < N { b',' } else { b']' })?;
        }
        Some(out)
    }

    /// A 4×4 array of numbers, row-major.
    fn matrix(&mut self) -> Option<Matrix4<f64>> {
        let mut m = Matrix4::zeros();
        self.eat(b'[')?;
        for r in 0..4 {
            self.space();
            let row: [f64; 4] = self.numbers()?;
            for (c, x) in row.into_iter().enumerate() {
                m[(r, c)] = x;
            }
            self.space();
            self.eat(if r < 3 { b',' } else { b']' })?;
        }
        Some(m)
    }
}

/// Powers of ten exactly representable as `f64`.
const EXACT_POWERS_OF_TEN: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// A number of the form `-?(0|[1-9][0-9]*)(.[0-9]+)?` with at most 19 digits, whose digits read as
/// an integer m ≤ 2⁵³ and with k ≤ 22 of them after the point, and what follows it is not part
/// of a number: its value m / 10ᵏ, and the bytes it takes. Both m and 10ᵏ are exact in `f64`,
/// so one division gives the correctly rounded value (Clinger's fast path: W. D. Clinger, "How to
/// read floating point numbers accurately", PLDI 1990). This is every number a recorder printing
/// up to 15 significant digits writes; anything else (an exponent, more digits, a malformed
/// number) is `None`, for lexical-core to decide.
fn short_decimal(bytes: &[u8]) -> Option<(f64, usize)> {
    let negative = bytes.first() == Some(&b'-');
    let mut at = usize::from(negative);
    let mut mantissa = 0u64;
    let integer = match bytes.get(at) {
        // JSON has no leading zeros: a 0 stands alone before the point.
        Some(b'0') => 1,
        Some(b'1'..=b'9') => digit_run(bytes, at, &mut mantissa),
        _ => return None,
    };
    at += integer;
    let mut after_point = 0;
    if bytes.get(at) == Some(&b'.') {
        after_point = digit_run(bytes, at + 1, &mut mantissa);
        if after_point == 0 {
            return None;
        }
        at += 1 + after_point;
    }
    // An exponent, or a digit after a leading zero, is another shape of number (or none).
    if integer + after_point > 19
        || after_point > 22
        || mantissa > 1 << 53
        || matches!(bytes.get(at), Some(b'e' | b'E' | b'0'..=b'9' | b'.'))
    {
        return None;
    }
    let magnitude = mantissa as f64 / EXACT_POWERS_OF_TEN[after_point];
    Some((if negative { -magnitude } else { magnitude }, at))
}

/// The number of ASCII digits from `at`, appended to `mantissa` (which wraps past 19 digits;
/// the caller refuses those). Eight digits at a time while eight are there (SWAR: D. Lemire,
/// "Number parsing at a gigabyte per second", Softw. Pract. Exp. 51, 2021, sec. 7), then one by
/// one.
fn digit_run(bytes: &[u8], at: usize, mantissa: &mut u64) -> usize {
    let rest = &bytes[at.min(bytes.len())..];
    let mut run = 0;
    while let Some(eight) = rest.get(run..run + 8).and_then(eight_digits) {
        *mantissa = mantissa.wrapping_mul(100_000_000).wrapping_add(eight);
        run += 8;
    }
    while let Some(&b) = rest.get(run) {
        let digit = b.wrapping_sub(b'0');
        if digit > 9 {
            break;
        }
        *mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(digit));
        run += 1;
    }
    run
}

/// The value of eight ASCII digits, or `None` when any byte is not a digit.
fn eight_digits(bytes: &[u8]) -> Option<u64> {
    let chunk = u64::from_le_bytes(bytes.try_into().ok()?);
    // A byte is a digit iff adding 0x46 does not carry into bit 7 and subtracting 0x30 does not
    // borrow from it.
    let digits = chunk.wrapping_sub(0x3030_3030_3030_3030);
    if (chunk.wrapping_add(0x4646_4646_4646_4646) | digits) & 0x8080_8080_8080_8080 != 0 {
        return None;
    }
    // Pairs, then fours, then the eight (the first digit is the lowest byte).
    let pairs = digits.wrapping_mul(10).wrapping_add(digits >> 8) & 0x00ff_00ff_00ff_00ff;
    let fours = pairs.wrapping_mul(100).wrapping_add(pairs >> 16) & 0x0000_ffff_0000_ffff;
    Some(fours.wrapping_mul(10_000).wrapping_add(fours >> 32) & 0xffff_ffff)
}

#[cfg(test)]
mod tests {
    use super::*;

    const I: &str = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";

    #[test]
    fn reads_the_common_shape_in_any_order_and_spacing() {
        let a = format!(r#"{{"stamp":1.5,"base_from_gripper":{I},"camera_from_target":{I}}}"#);
        let b = format!(
            "{{ \"target_from_camera\" : {} ,\t\"gripper_from_base\": {I}, \"stamp\": null }}",
            I.replace(',', " , ")
        );
        let a = scan(&a).unwrap();
        assert_eq!(a.stamp, Some(1.5));
        assert_eq!((a.robot.1, a.camera.1), (false, false));
        assert_eq!(a.robot.0.matrix, Some(Matrix4::identity()));
        let b = scan(&b).unwrap();
        assert_eq!(b.stamp, None);
        assert_eq!((b.robot.1, b.camera.1), (true, true));
        assert_eq!(b.camera.0.matrix, Some(Matrix4::identity()));
        let parts = format!(
            r#"{{"base_from_gripper":{{"translation":[1,2,3],"quaternion_xyzw":[0,0,0,1]}},"camera_from_target":{{"matrix":{I},"translation":[0,0,0]}}}}"#
        );
        let c = scan(&parts).unwrap();
        assert_eq!(c.robot.0.translation, Some([1.0, 2.0, 3.0]));
        assert_eq!(c.robot.0.quaternion_xyzw, Some([0.0, 0.0, 0.0, 1.0]));
        assert_eq!(c.robot.0.matrix, None);
        assert_eq!(c.camera.0.quaternion_xyzw, None);
    }

    #[test]
    fn leaves_every_other_shape_to_the_general_path() {
        let rest = format!(r#""base_from_gripper":{I},"camera_from_target":{I}"#);
        let lines = [
            format!("{{{rest},\"frame\":\"tool0\"}}"),
            format!("{{{rest},\"stamp\":1,\"stamp\":2}}"),
            format!("{{{rest},\"gripper_from_base\":{I}}}"),
            format!("{{\"stamp\":\"1\",{rest}}}"),
            format!("{{\"stamp\":1e400,{rest}}}"),
            format!("{{\"stamp\":01,{rest}}}"),
            format!("{{\"stamp\":1.,{rest}}}"),
            format!("{{\"stamp\":.5,{rest}}}"),
            format!("{{\"stamp\":+1,{rest}}}"),
            format!("{{\"st\\u0061mp\":1,{rest}}}"),
            format!("{{{rest}}} x"),
            format!("{{{rest},}}"),
            format!("{{{rest}"),
            format!("{{\"base_from_gripper\":{I}}}"),
            format!(
                "{{\"base_from_gripper\":{{\"matrix\":{I},\"frame\":1}},\"camera_from_target\":{I}}}"
            ),
            format!(
                "{{\"base_from_gripper\":{{\"matrix\":{I},\"matrix\":{I}}},\"camera_from_target\":{I}}}"
            ),
            format!(
                "{{\"base_from_gripper\":{{\"translation\":[1,2]}},\"camera_from_target\":{I}}}"
            ),
            format!(
                "{{\"base_from_gripper\":[[1,0,0,0],[0,1,0,0],[0,0,1,0]],\"camera_from_target\":{I}}}"
            ),
            format!(
                "{{\"base_from_gripper\":[[1,0,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]],\"camera_from_target\":{I}}}"
            ),
            "{}".to_string(),
            String::new(),
        ];
        for line in lines {
            assert_eq!(scan(&line), None, "{line}");
        }
    }

    #[test]
    fn eight_digits_read_as_their_value_and_anything_else_does_not() {
        for n in [
            0u64, 1, 9, 10, 12_345_678, 99_999_999, 80_000_000, 10_000_001,
        ] {
            assert_eq!(eight_digits(format!("{n:08}").as_bytes()), Some(n));
        }
        for text in [
            "1234567a", "/1234567", ":1234567", "1234 678", "12345.78", "-1234567",
        ] {
            assert_eq!(eight_digits(text.as_bytes()), None, "{text}");
        }
        assert_eq!(eight_digits(b"1234567"), None);
    }

    #[test]
    fn short_decimals_take_the_fast_path_and_others_do_not() {
        for (text, value, used) in [
            ("0.8463557237,", 0.8463557237, 12),
            ("-0.02751717222]", -0.02751717222, 14),
            ("-0", -0.0, 2),
            ("14.5319036412205", 14.5319036412205, 16),
            ("9007199254740992 ", 9007199254740992.0, 16),
        ] {
            let (x, n) = short_decimal(text.as_bytes()).unwrap();
            assert_eq!((x.to_bits(), n), (f64::to_bits(value), used), "{text}");
        }
        // Over 2⁵³, over 19 digits, an exponent, a leading zero, a bare point: lexical-core's.
        for text in [
            "9007199254740993",
            "0.12345678901234567890",
            "1e5",
            "1.5E-3",
            "01",
            "1.",
            ".5",
            "-",
            "+1",
            "",
        ] {
            assert_eq!(short_decimal(text.as_bytes()), None, "{text}");
        }
    }

    proptest::proptest! {
        /// Numbers as recorders print them (the fast path's), bit for bit serde_json's.
        #[test]
        fn printed_decimals_are_serde_jsons(text in "-?(0|[1-9][0-9]{0,9})\\.[0-9]{1,17}") {
            let line = format!(
                "{{\"stamp\":{text},\"base_from_gripper\":{I},\"camera_from_target\":{I}}}"
            );
            let serde: f64 = serde_json::from_str(&text).unwrap();
            let fast = scan(&line).unwrap().stamp.unwrap();
            proptest::prop_assert_eq!(fast.to_bits(), serde.to_bits());
        }

        /// Every number JSON allows converts to serde_json's own value, bit for bit.
        #[test]
        fn numbers_are_serde_jsons(
            text in "-?(0|[1-9][0-9]{0,24})(\\.[0-9]{1,24})?([eE][+-]?[0-9]{1,4})?"
        ) {
            let line = format!(
                "{{\"stamp\":{text},\"base_from_gripper\":{I},\"camera_from_target\":{I}}}"
            );
            let serde: Option<f64> = serde_json::from_str(&text).ok();
            let fast = scan(&line).map(|s| s.stamp.unwrap());
            proptest::prop_assert_eq!(fast.map(f64::to_bits), serde.map(f64::to_bits));
        }

        /// Any bytes are scanned without panic.
        #[test]
        fn any_bytes_are_scanned_without_panic(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..80)) {
            let _ = scan(&String::from_utf8_lossy(&bytes));
        }
    }
}
