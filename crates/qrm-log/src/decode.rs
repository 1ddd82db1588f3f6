//! Decoding one message of a readable [`Kind`] into a [`RangeScan`] or a [`DetectionMessage`].
//!
//! Scans are brought to one canonical form whatever their source, so the same scan read from
//! a ROS 2 bag and from a Foxglove JSON log gives bit-identical landmarks: ranges are `f32`
//! (what ROS carries and what a lidar resolves), the first angle and the increment are `f32`
//! (`foxglove.LaserScan` gives the first and last angle; its increment is
//! `(end − start)/(n − 1)` rounded to `f32`), and ray `i` lies at `start + i·increment` in
//! `f64`.

use serde::Deserialize;
use serde_json::Value;

use crate::kind::Kind;

/// The most rays one scan may have (a 0.01° lidar has 36,000).
pub const MAX_RAYS: usize = 1 << 20;

/// One lidar scan in canonical form.
#[derive(Debug, Clone, PartialEq)]
pub struct RangeScan {
    /// Time stamp (s).
    pub t: f64,
    /// Angle of the first ray (rad, sensor frame).
    pub angle_min: f32,
    /// Angle between rays (rad).
    pub angle_increment: f32,
    /// Returns below this are no return (m).
    pub range_min: f32,
    /// Returns above this are no return (m).
    pub range_max: f32,
    /// Ranges (m); non-finite = no return.
    pub ranges: Vec<f32>,
}

impl RangeScan {
    /// The scan as the extractor takes it: angles in `f64`, no return as infinity.
    #[must_use]
    pub fn to_laser_scan(&self) -> sim2d::LaserScan {
        let a0 = f64::from(self.angle_min);
        let da = f64::from(self.angle_increment);
        let angles = (0..self.ranges.len()).map(|i| a0 + i as f64 * da).collect();
        let ranges = self
            .ranges
            .iter()
            .map(|&r| {
                if r.is_finite() && r > 0.0 && r >= self.range_min && r <= self.range_max {
                    f64::from(r)
                } else {
                    f64::INFINITY
                }
            })
            .collect();
        sim2d::LaserScan {
            angles,
            ranges,
            hits: vec![None; self.ranges.len()],
        }
    }
}

/// One landmark detection: id, position (m, sensor frame), covariance `[cxx, cxy, cyy]` (m²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Detection {
    /// Landmark id.
    pub id: u32,
    /// Position (m).
    pub xy: [f64; 2],
    /// Covariance `[cxx, cxy, cyy]` (m²).
    pub cov: [f64; 3],
}

/// One `qrm.LandmarkDetections` message.
#[derive(Debug, Clone, PartialEq)]
pub struct DetectionMessage {
    /// Time stamp (s): the exact `t` field when present, else `timestamp`.
    pub t: f64,
    /// The detections.
    pub detections: Vec<Detection>,
}

/// A decoded message.
#[derive(Debug, Clone, PartialEq)]
pub enum Decoded {
    /// A lidar scan.
    Scan(RangeScan),
    /// Landmark detections with ids.
    Detections(DetectionMessage),
}

/// What is wrong with a message: the field (dotted path) and the reason.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FieldError {
    /// The field.
    pub field: String,
    /// The reason.
    pub reason: String,
}

fn bad(field: impl Into<String>, reason: impl Into<String>) -> FieldError {
    FieldError {
        field: field.into(),
        reason: reason.into(),
    }
}

/// Decodes `bytes` as a message of `kind`. `range_limits` (min, max) override or complete
/// what the message says (Foxglove scans carry none).
///
/// # Errors
/// A [`FieldError`] naming the field that cannot be decoded or holds an impossible value.
pub fn decode(
    kind: Kind,
    bytes: &[u8],
    range_limits: (Option<f32>, Option<f32>),
) -> Result<Decoded, FieldError> {
    match kind {
        Kind::Ros2LaserScan => ros2_scan(bytes, range_limits).map(Decoded::Scan),
        Kind::FoxgloveLaserScan => foxglove_scan(bytes, range_limits).map(Decoded::Scan),
        Kind::Detections => detections(bytes).map(Decoded::Detections),
    }
}

fn time(sec: f64, nsec: f64, field: &str) -> Result<f64, FieldError> {
    if !(0.0..1e9).contains(&nsec) || nsec.fract() != 0.0 {
        return Err(bad(
            format!("{field}.nsec"),
            format!("{nsec} is not a whole number of nanoseconds below 1e9"),
        ));
    }
    if !sec.is_finite() || sec.fract() != 0.0 {
        return Err(bad(format!("{field}.sec"), format!("{sec} is not whole")));
    }
    Ok(sec + nsec * 1e-9)
}

fn check_scan(s: RangeScan) -> Result<RangeScan, FieldError> {
    if s.ranges.len() > MAX_RAYS {
        return Err(bad(
            "ranges",
            format!("{} rays, more than {MAX_RAYS}", s.ranges.len()),
        ));
    }
    if !s.angle_min.is_finite() {
        return Err(bad("angle_min", format!("{} is not finite", s.angle_min)));
    }
    if !s.angle_increment.is_finite() || s.angle_increment.abs() > 1.0 {
        return Err(bad(
            "angle_increment",
            format!(
                "{} rad is not a lidar's ray spacing (finite, at most 1 rad)",
                s.angle_increment
            ),
        ));
    }
    if s.range_min.is_nan() || s.range_max.is_nan() || s.range_min > s.range_max {
        return Err(bad(
            "range_min",
            format!("[{}, {}] is not a range interval", s.range_min, s.range_max),
        ));
    }
    Ok(s)
}

/// ROS 2 `builtin_interfaces/msg/Time`.
#[derive(Deserialize)]
struct RosTime {
    sec: i32,
    nanosec: u32,
}

/// ROS 2 `std_msgs/msg/Header`.
#[derive(Deserialize)]
struct RosHeader {
    stamp: RosTime,
    #[allow(dead_code)]
    frame_id: String,
}

/// ROS 2 `sensor_msgs/msg/LaserScan`, field for field in CDR order.
#[derive(Deserialize)]
#[allow(dead_code)]
struct RosLaserScan {
    header: RosHeader,
    angle_min: f32,
    angle_max: f32,
    angle_increment: f32,
    time_increment: f32,
    scan_time: f32,
    range_min: f32,
    range_max: f32,
    ranges: Vec<f32>,
    intensities: Vec<f32>,
}

/// CDR behind its 4-byte encapsulation header (representation id, options); alignment counts
/// from the end of the header.
fn ros2_scan(
    bytes: &[u8],
    (min, max): (Option<f32>, Option<f32>),
) -> Result<RangeScan, FieldError> {
    let (head, body) = bytes.split_at_checked(4).ok_or_else(|| {
        bad(
            "encapsulation",
            "message shorter than the 4-byte CDR header",
        )
    })?;
    let decoded = match [head[0], head[1]] {
        [0, 0] => cdr_encoding::from_bytes::<RosLaserScan, byteorder::BigEndian>(body),
        [0, 1] => cdr_encoding::from_bytes::<RosLaserScan, byteorder::LittleEndian>(body),
        other => {
            return Err(bad(
                "encapsulation",
                format!("representation {other:02x?} is not plain CDR (00 00 or 00 01)"),
            ));
        }
    };
    let (m, _) =
        decoded.map_err(|e| bad("(cdr)", format!("not a sensor_msgs/msg/LaserScan: {e}")))?;
    let t = time(
        f64::from(m.header.stamp.sec),
        f64::from(m.header.stamp.nanosec),
        "header.stamp",
    )?;
    let (range_min, range_max) = limits((min, max), (m.range_min, m.range_max))?;
    check_scan(RangeScan {
        t,
        angle_min: m.angle_min,
        angle_increment: m.angle_increment,
        range_min,
        range_max,
        ranges: m.ranges,
    })
}

/// The range limits a scan is read with: the reader's overrides (`--range-max`) where given,
/// else the message's. An override that leaves no interval is blamed, not the message (issue
/// 39: `--range-max 0` was reported as the message's `range_min` being wrong).
fn limits(
    (min, max): (Option<f32>, Option<f32>),
    (message_min, message_max): (f32, f32),
) -> Result<(f32, f32), FieldError> {
    let (lo, hi) = (min.unwrap_or(message_min), max.unwrap_or(message_max));
    if max.is_some() && lo > hi {
        return Err(bad(
            "range_max",
            format!("the --range-max given ({hi} m) is below the scan's range_min ({lo} m)"),
        ));
    }
    if min.is_some() && lo > hi {
        return Err(bad(
            "range_min",
            format!("the range_min given ({lo} m) is above the scan's range_max ({hi} m)"),
        ));
    }
    Ok((lo, hi))
}

fn json(bytes: &[u8]) -> Result<Value, FieldError> {
    serde_json::from_slice(bytes).map_err(|e| bad("(json)", e.to_string()))
}

fn number(v: &Value, field: &str) -> Result<f64, FieldError> {
    let x = v
        .as_f64()
        .ok_or_else(|| bad(field, format!("{} is not a number", shown(v))))?;
    if x.is_finite() {
        Ok(x)
    } else {
        Err(bad(field, "not finite"))
    }
}

/// A JSON value for a message, cut short.
fn shown(v: &Value) -> String {
    let s = v.to_string();
    match s.char_indices().nth(40) {
        Some((i, _)) => format!("{}…", &s[..i]),
        None => s,
    }
}

fn stamp(m: &Value, field: &str) -> Result<f64, FieldError> {
    let ts = m.get(field).ok_or_else(|| bad(field, "missing"))?;
    time(
        number(
            ts.get("sec").unwrap_or(&Value::Null),
            &format!("{field}.sec"),
        )?,
        number(
            ts.get("nsec").unwrap_or(&Value::Null),
            &format!("{field}.nsec"),
        )?,
        field,
    )
}

fn foxglove_scan(
    bytes: &[u8],
    (min, max): (Option<f32>, Option<f32>),
) -> Result<RangeScan, FieldError> {
    let m = json(bytes)?;
    let t = stamp(&m, "timestamp")?;
    let start = number(m.get("start_angle").unwrap_or(&Value::Null), "start_angle")?;
    let end = number(m.get("end_angle").unwrap_or(&Value::Null), "end_angle")?;
    let list = m
        .get("ranges")
        .and_then(Value::as_array)
        .ok_or_else(|| bad("ranges", "missing or not an array"))?;
    let mut ranges = Vec::with_capacity(list.len().min(MAX_RAYS));
    for (i, r) in list.iter().enumerate() {
        // null is how JSON spells a missing return; anything else must be a number.
        ranges.push(match r {
            Value::Null => f32::NAN,
            v => v.as_f64().ok_or_else(|| {
                bad(
                    format!("ranges[{i}]"),
                    format!("{} is not a number", shown(v)),
                )
            })? as f32,
        });
    }
    let n = ranges.len();
    let increment = if n > 1 {
        (end - start) / (n - 1) as f64
    } else {
        0.0
    };
    let (range_min, range_max) = limits((min, max), (0.0, f32::INFINITY))?;
    check_scan(RangeScan {
        t,
        angle_min: start as f32,
        angle_increment: increment as f32,
        range_min,
        range_max,
        ranges,
    })
}

fn detections(bytes: &[u8]) -> Result<DetectionMessage, FieldError> {
    let m = json(bytes)?;
    let t = match m.get("t") {
        Some(v) => number(v, "t")?,
        None => stamp(&m, "timestamp")?,
    };
    let list = m
        .get("detections")
        .and_then(Value::as_array)
        .ok_or_else(|| bad("detections", "missing or not an array"))?;
    let mut out = Vec::with_capacity(list.len());
    for (i, d) in list.iter().enumerate() {
        let f = |name: &str| format!("detections[{i}].{name}");
        let id_value = d.get("id").unwrap_or(&Value::Null);
        let id = id_value
            .as_u64()
            .and_then(|v| u32::try_from(v).ok())
            .ok_or_else(|| {
                bad(
                    f("id"),
                    format!(
                        "{} is not a whole number in 0..=4294967295",
                        shown(id_value)
                    ),
                )
            })?;
        let x = number(d.get("x").unwrap_or(&Value::Null), &f("x"))?;
        let y = number(d.get("y").unwrap_or(&Value::Null), &f("y"))?;
        let cov = d
            .get("cov")
            .and_then(Value::as_array)
            .filter(|c| c.len() == 3)
            .ok_or_else(|| bad(f("cov"), "missing or not [cxx, cxy, cyy]"))?;
        let mut c = [0.0; 3];
        for (k, v) in cov.iter().enumerate() {
            c[k] = number(v, &format!("{}[{k}]", f("cov")))?;
        }
        out.push(Detection {
            id,
            xy: [x, y],
            cov: c,
        });
    }
    Ok(DetectionMessage { t, detections: out })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sensor_msgs/msg/LaserScan in little-endian CDR, laid out by hand from the IDL
    /// (independently of the decoder's serde structs): header, seven floats, two sequences.
    fn cdr_scan(sec: i32, nanosec: u32, frame: &str, ranges: &[f32]) -> Vec<u8> {
        let mut b = vec![0u8, 1, 0, 0];
        let body_start = b.len();
        let align = |b: &mut Vec<u8>, n: usize| {
            while !(b.len() - body_start).is_multiple_of(n) {
                b.push(0);
            }
        };
        b.extend_from_slice(&sec.to_le_bytes());
        b.extend_from_slice(&nanosec.to_le_bytes());
        b.extend_from_slice(&(frame.len() as u32 + 1).to_le_bytes());
        b.extend_from_slice(frame.as_bytes());
        b.push(0);
        align(&mut b, 4);
        for v in [-1.5f32, 1.5, 0.25, 0.0, 0.1, 0.05, 30.0] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&(ranges.len() as u32).to_le_bytes());
        for r in ranges {
            b.extend_from_slice(&r.to_le_bytes());
        }
        b.extend_from_slice(&0u32.to_le_bytes());
        b
    }

    #[test]
    fn ros2_laser_scan_decodes_from_cdr_bytes_laid_out_by_hand() {
        let bytes = cdr_scan(12, 500_000_000, "laser", &[1.0, 2.0, 40.0, 0.01]);
        let Decoded::Scan(s) = decode(Kind::Ros2LaserScan, &bytes, (None, None)).unwrap() else {
            panic!("not a scan")
        };
        assert_eq!(s.t, 12.5);
        assert_eq!((s.angle_min, s.angle_increment), (-1.5, 0.25));
        assert_eq!((s.range_min, s.range_max), (0.05, 30.0));
        // Beyond range_max (40) and below range_min (0.01) are no return.
        let l = s.to_laser_scan();
        assert_eq!(l.ranges[..2], [1.0, 2.0]);
        assert!(l.ranges[2].is_infinite() && l.ranges[3].is_infinite());
        assert_eq!(l.angles, vec![-1.5, -1.25, -1.0, -0.75]);
    }

    #[test]
    fn a_truncated_cdr_message_names_the_decoding_failure() {
        let bytes = cdr_scan(1, 0, "laser", &[1.0, 2.0]);
        let e = decode(Kind::Ros2LaserScan, &bytes[..bytes.len() - 6], (None, None)).unwrap_err();
        assert_eq!(e.field, "(cdr)");
        let e = decode(Kind::Ros2LaserScan, &[0, 9, 0, 0, 1], (None, None)).unwrap_err();
        assert_eq!(e.field, "encapsulation");
    }

    #[test]
    fn foxglove_scan_and_ros2_scan_of_the_same_rays_agree_bit_for_bit() {
        let ranges = [1.25f32, 2.5, 3.75, 5.0];
        let (start, end) = (-1.5f64, -0.75f64);
        let fox = serde_json::json!({"timestamp": {"sec": 12, "nsec": 500_000_000},
            "start_angle": start, "end_angle": end, "ranges": ranges});
        let Decoded::Scan(f) = decode(
            Kind::FoxgloveLaserScan,
            fox.to_string().as_bytes(),
            (None, Some(30.0)),
        )
        .unwrap() else {
            panic!()
        };
        let ros = cdr_scan(12, 500_000_000, "laser", &ranges);
        let Decoded::Scan(r) = decode(Kind::Ros2LaserScan, &ros, (None, None)).unwrap() else {
            panic!()
        };
        assert_eq!(f.to_laser_scan().angles, r.to_laser_scan().angles);
        assert_eq!(f.to_laser_scan().ranges, r.to_laser_scan().ranges);
    }

    #[test]
    fn detections_name_the_bad_field() {
        let m = br#"{"timestamp": {"sec": 1, "nsec": 0}, "detections": [{"id": 3, "x": 1, "y": 2, "cov": [0.1, 0, 0.1]}, {"id": -4, "x": 1, "y": 2, "cov": [0.1, 0, 0.1]}]}"#;
        let e = decode(Kind::Detections, m, (None, None)).unwrap_err();
        assert_eq!(e.field, "detections[1].id");
        let m = br#"{"timestamp": {"sec": 1, "nsec": 1e9}, "detections": []}"#;
        assert_eq!(
            decode(Kind::Detections, m, (None, None)).unwrap_err().field,
            "timestamp.nsec"
        );
        let m = br#"{"t": 0.1, "detections": [{"id": 3, "x": 1, "y": 2, "cov": [0.1, 0]}]}"#;
        assert_eq!(
            decode(Kind::Detections, m, (None, None)).unwrap_err().field,
            "detections[0].cov"
        );
    }
}
