//! Sensor drivers on `embedded-hal` 1.0 traits — not written yet (MPU-9250 and MS5611 over SPI,
//! GPS UBX/NMEA, laser and sonar serial lines, each host-tested on datasheet byte sequences).
