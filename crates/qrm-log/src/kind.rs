//! Which messages qrm reads: a channel's schema name and encodings decide its [`Kind`].

/// A readable kind of message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Kind {
    /// `sensor_msgs/msg/LaserScan` in ROS 2 CDR (what `ros2 bag record` writes).
    Ros2LaserScan,
    /// `foxglove.LaserScan` in JSON (what `qrm sim` writes).
    FoxgloveLaserScan,
    /// `qrm.LandmarkDetections` in JSON: landmarks with ids and covariances.
    Detections,
}

/// What a user is told can be read.
pub const READABLE: &str = "sensor_msgs/msg/LaserScan (ros2msg schema, cdr messages), foxglove.LaserScan (json), qrm.LandmarkDetections (json)";

impl Kind {
    /// The kind of a channel, `None` when qrm cannot read it. ROS 1 and ROS 2 spell the
    /// LaserScan type with or without `/msg/`; protobuf and other encodings are not read.
    #[must_use]
    pub fn of(schema_name: &str, schema_encoding: &str, message_encoding: &str) -> Option<Self> {
        match (schema_name, message_encoding) {
            ("sensor_msgs/msg/LaserScan" | "sensor_msgs/LaserScan", "cdr")
                if matches!(schema_encoding, "ros2msg" | "ros2idl" | "") =>
            {
                Some(Self::Ros2LaserScan)
            }
            ("foxglove.LaserScan", "json") => Some(Self::FoxgloveLaserScan),
            ("qrm.LandmarkDetections", "json") => Some(Self::Detections),
            _ => None,
        }
    }

    /// Whether the messages are raw scans (landmarks found by the extractor and recognised
    /// without ids) rather than detections with ids.
    #[must_use]
    pub fn is_scan(self) -> bool {
        matches!(self, Self::Ros2LaserScan | Self::FoxgloveLaserScan)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_are_recognised_by_schema_and_encoding() {
        assert_eq!(
            Kind::of("sensor_msgs/msg/LaserScan", "ros2msg", "cdr"),
            Some(Kind::Ros2LaserScan)
        );
        assert_eq!(
            Kind::of("foxglove.LaserScan", "jsonschema", "json"),
            Some(Kind::FoxgloveLaserScan)
        );
        // The same schema name in protobuf is not JSON: not readable.
        assert_eq!(Kind::of("foxglove.LaserScan", "protobuf", "protobuf"), None);
        assert_eq!(Kind::of("sensor_msgs/msg/Imu", "ros2msg", "cdr"), None);
        assert!(Kind::Ros2LaserScan.is_scan() && !Kind::Detections.is_scan());
    }
}
