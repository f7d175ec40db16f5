//! The CSV of resampled postures (`crest resample`), written through the `csv` crate one
//! sample at a time, so that memory does not grow with the output. Columns: [`HEADER`];
//! the CC point and normal are empty where the path has no contact data, the time and feed
//! where no feed is known.

use crate::resample::Sample;
use crate::toolpath::write::push_decimals;
use std::io::Write;

/// The CSV header, in column order.
pub const HEADER: &str = "s_mm,t_s,theta_deg,x,y,z,i,j,k,cx,cy,cz,nx,ny,nz,fx,fy,fz,feed_mm_min";

/// Decimals of the columns: lengths and angles 6, time and unit vectors 9, feed 3.
const LEN: u32 = 6;
const UNIT: u32 = 9;
const FEED: u32 = 3;

/// The sample sink: the first write error is kept and reported by [`SampleCsv::check`].
pub struct SampleCsv<'w> {
    w: csv::Writer<&'w mut dyn Write>,
    /// The digits of the current row's fields, and where each ends.
    digits: Vec<u8>,
    ends: Vec<usize>,
    error: Option<std::io::Error>,
}

impl<'w> SampleCsv<'w> {
    /// A sink writing to `w` (the header first).
    pub fn new(w: &'w mut dyn Write) -> std::io::Result<SampleCsv<'w>> {
        let mut w = csv::WriterBuilder::new()
            .buffer_capacity(1 << 16)
            .from_writer(w);
        w.write_record(HEADER.split(','))?;
        Ok(SampleCsv {
            w,
            digits: Vec::with_capacity(256),
            ends: Vec::with_capacity(19),
            error: None,
        })
    }

    /// Write one sample (errors are kept for [`SampleCsv::check`]).
    pub fn sample(&mut self, s: &Sample) {
        if self.error.is_some() {
            return;
        }
        fields(&mut self.digits, &mut self.ends, s);
        let mut start = 0;
        let digits = &self.digits;
        let record = self.ends.iter().map(|&end| {
            let f = &digits[start..end];
            start = end;
            f
        });
        if let Err(e) = self.w.write_record(record) {
            self.error = Some(e.into());
        }
    }

    /// The first write error, if any.
    pub fn check(&mut self) -> std::io::Result<()> {
        match self.error.take() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// Write out what is buffered.
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.check()?;
        self.w.flush()
    }
}

/// The fields of `s` into `digits` (field k ends at `ends[k]`): the digits of `{:.6}`
/// (lengths, θ), `{:.9}` (t, unit vectors) and `{:.3}` (feed); empty where unknown.
fn fields(digits: &mut Vec<u8>, ends: &mut Vec<usize>, s: &Sample) {
    digits.clear();
    ends.clear();
    let mut num = |v: Option<f64>, dec: u32| {
        if let Some(v) = v {
            push_decimals(digits, v, dec);
        }
        ends.push(digits.len());
    };
    let known = |v: f64| (!v.is_nan()).then_some(v);
    let (p, a, f) = (&s.position, &s.axis, &s.feed_dir);
    num(Some(s.s_mm), LEN);
    num(known(s.t_s), UNIT);
    num(Some(s.theta_rad.to_degrees()), LEN);
    for v in [p.x, p.y, p.z] {
        num(Some(v), LEN);
    }
    for v in [a.x, a.y, a.z] {
        num(Some(v), UNIT);
    }
    for k in 0..3 {
        num(s.contact.map(|c| c[k]), LEN);
    }
    for k in 0..3 {
        num(s.normal.map(|n| n[k]), UNIT);
    }
    for v in [f.x, f.y, f.z] {
        num(Some(v), UNIT);
    }
    num(known(s.feed_mm_min), FEED);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Point3, Vec3};

    #[test]
    fn row_has_every_column_and_empty_contact() {
        let s = Sample {
            run: 0,
            s_mm: 1.5,
            t_s: 0.25,
            theta_rad: std::f64::consts::PI,
            position: Point3::new(1.0, 2.0, 3.0),
            axis: Vec3::z(),
            contact: None,
            normal: None,
            feed_dir: Vec3::x(),
            feed_mm_min: 1000.0,
        };
        let mut out = Vec::new();
        {
            let mut csv = SampleCsv::new(&mut out).unwrap();
            csv.sample(&s);
            let mut t = s.clone();
            t.t_s = f64::NAN;
            t.feed_mm_min = f64::NAN;
            t.contact = Some(Point3::new(0.5, -0.25, 1.0));
            t.normal = Some(Vec3::z());
            csv.sample(&t);
            csv.flush().unwrap();
        }
        let text = String::from_utf8(out).unwrap();
        let rows: Vec<&str> = text.lines().collect();
        assert_eq!(rows[0], HEADER);
        assert_eq!(
            rows[1],
            "1.500000,0.250000000,180.000000,1.000000,2.000000,3.000000,\
             0.000000000,0.000000000,1.000000000,,,,,,,1.000000000,0.000000000,0.000000000,1000.000"
        );
        assert_eq!(
            rows[2],
            "1.500000,,180.000000,1.000000,2.000000,3.000000,\
             0.000000000,0.000000000,1.000000000,0.500000,-0.250000,1.000000,\
             0.000000000,0.000000000,1.000000000,1.000000000,0.000000000,0.000000000,"
        );
        assert_eq!(rows[1].split(',').count(), HEADER.split(',').count());
    }
}
