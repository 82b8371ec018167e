//! Properties of the sampler: stratification of every 2D projection and every dimension,
//! independence across pixels and dimensions, determinism per seed.

use super::*;

/// Draws `pairs_before` 2D pairs and returns the next pair, for sample `index` of `pixel`.
fn pair(sampler: Sampler, pixel: u32, index: u32, pairs_before: u32) -> Vec2 {
    let mut s = sampler.pixel(pixel, index);
    for _ in 0..pairs_before {
        s.next_2d();
    }
    s.next_2d()
}

fn correlation(a: &[f32], b: &[f32]) -> f64 {
    let n = a.len() as f64;
    let mean = |v: &[f32]| v.iter().map(|&x| x as f64).sum::<f64>() / n;
    let (ma, mb) = (mean(a), mean(b));
    let cov: f64 = a
        .iter()
        .zip(b)
        .map(|(&x, &y)| (x as f64 - ma) * (y as f64 - mb))
        .sum();
    let var = |v: &[f32], m: f64| v.iter().map(|&x| (x as f64 - m).powi(2)).sum::<f64>();
    cov / (var(a, ma) * var(b, mb)).sqrt()
}

#[test]
fn the_first_power_of_two_samples_of_every_pair_form_a_net() {
    // One point in every elementary interval 2^-a x 2^-(k-a) of area 2^-k: the (0,k,2)-net
    // property, for every pixel, every pair of dimensions and every prefix 2^k.
    for seed in [0u32, 9] {
        let sampler = Sampler::new(seed);
        for pixel in [0u32, 1, 641, 921_599] {
            for pairs_before in [0u32, 1, 2, 7] {
                for k in [1u32, 2, 4, 6] {
                    let points: Vec<Vec2> = (0..1 << k)
                        .map(|i| pair(sampler, pixel, i, pairs_before))
                        .collect();
                    for a in 0..=k {
                        let (nx, ny) = ((1u32 << a) as f32, (1u32 << (k - a)) as f32);
                        let mut cells = vec![0u32; 1 << k];
                        for p in &points {
                            assert!((0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y));
                            let (cx, cy) = ((p.x * nx) as u32, (p.y * ny) as u32);
                            cells[(cy * nx as u32 + cx) as usize] += 1;
                        }
                        assert!(
                            cells.iter().all(|&c| c == 1),
                            "seed {seed} pixel {pixel} pair {pairs_before} k {k} a {a}: {cells:?}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn single_dimensions_are_stratified() {
    let sampler = Sampler::new(0);
    for pixel in [3u32, 77] {
        for dims_before in [0u32, 1, 5] {
            let n = 64u32;
            let mut cells = vec![0u32; n as usize];
            for i in 0..n {
                let mut s = sampler.pixel(pixel, i);
                for _ in 0..dims_before {
                    s.next_1d();
                }
                let v = s.next_1d();
                assert!((0.0..1.0).contains(&v));
                cells[(v * n as f32) as usize] += 1;
            }
            assert!(
                cells.iter().all(|&c| c == 1),
                "{pixel} {dims_before}: {cells:?}"
            );
        }
    }
}

#[test]
fn neighbouring_pixels_are_uncorrelated() {
    // Same sample index and dimension in pixels p and p + 1 (and p + width): a sampler that
    // reused one point set for all pixels would give correlation 1.
    let sampler = Sampler::new(0);
    let width = 320u32;
    for index in [0u32, 1, 5, 16] {
        for pairs_before in [0u32, 3] {
            let here: Vec<Vec2> = (0..8192)
                .map(|p| pair(sampler, p, index, pairs_before))
                .collect();
            let right: Vec<Vec2> = (0..8192)
                .map(|p| pair(sampler, p + 1, index, pairs_before))
                .collect();
            let below: Vec<Vec2> = (0..8192)
                .map(|p| pair(sampler, p + width, index, pairs_before))
                .collect();
            for other in [&right, &below] {
                for axis in 0..2 {
                    let a: Vec<f32> = here.iter().map(|v| v[axis]).collect();
                    let b: Vec<f32> = other.iter().map(|v| v[axis]).collect();
                    let r = correlation(&a, &b);
                    // 4 standard deviations of r for 8192 independent pairs.
                    assert!(
                        r.abs() < 4.0 / 8192f64.sqrt(),
                        "index {index} axis {axis}: r {r}"
                    );
                }
            }
        }
    }
}

#[test]
fn pairs_of_dimensions_are_uncorrelated() {
    // Over all samples of many pixels: the x (and y) of one pair against those of the next
    // pairs, and the two coordinates of one pair against each other.
    let sampler = Sampler::new(0);
    let mut draws: Vec<[Vec2; 3]> = Vec::new();
    for pixel in 0..1024u32 {
        for index in 0..16u32 {
            let mut s = sampler.pixel(pixel, index);
            draws.push([s.next_2d(), s.next_2d(), s.next_2d()]);
        }
    }
    let n = draws.len() as f64;
    let column =
        |pair: usize, axis: usize| -> Vec<f32> { draws.iter().map(|d| d[pair][axis]).collect() };
    for (a, b) in [
        ((0, 0), (1, 0)),
        ((0, 1), (1, 1)),
        ((0, 0), (2, 0)),
        ((1, 0), (2, 1)),
        ((0, 0), (0, 1)),
    ] {
        let r = correlation(&column(a.0, a.1), &column(b.0, b.1));
        assert!(r.abs() < 4.0 / n.sqrt(), "{a:?} vs {b:?}: r {r}");
    }
    // Within one pixel the pairs are not the same point set in the same order either: the
    // 16 samples' quadrants in pair 0 and pair 1 agree in about a quarter of cases.
    let quadrant = |v: Vec2| (v.x >= 0.5) as u32 * 2 + (v.y >= 0.5) as u32;
    let agree = draws
        .iter()
        .filter(|d| quadrant(d[0]) == quadrant(d[1]))
        .count() as f64;
    assert!((agree / n - 0.25).abs() < 0.02, "{}", agree / n);
}

#[test]
fn values_are_uniform() {
    let sampler = Sampler::new(5);
    let values: Vec<f32> = (0..20_000u32)
        .map(|p| sampler.pixel(p, 3).next_1d())
        .collect();
    let mean = values.iter().map(|&v| v as f64).sum::<f64>() / values.len() as f64;
    let variance = values
        .iter()
        .map(|&v| (v as f64 - mean).powi(2))
        .sum::<f64>()
        / values.len() as f64;
    assert!((mean - 0.5).abs() < 0.01, "mean {mean}");
    assert!((variance - 1.0 / 12.0).abs() < 0.003, "variance {variance}");
}

#[test]
fn the_seed_alone_decides_the_values() {
    let draw = |seed: u32| {
        let mut s = Sampler::new(seed).pixel(1234, 7);
        [s.next_1d(), s.next_2d().x, s.next_2d().y, s.next_1d()]
    };
    assert_eq!(draw(0), draw(0));
    assert_eq!(draw(41), draw(41));
    let (a, b) = (draw(0), draw(1));
    assert!(a.iter().zip(&b).all(|(x, y)| x != y), "{a:?} {b:?}");
    assert_eq!(Sampler::default(), Sampler::new(0));
}

#[test]
fn the_camera_takes_four_dimensions_and_one_sample_sits_at_the_centre() {
    let sampler = Sampler::new(0);
    let mut one = sampler.pixel(10, 0);
    let single = one.camera_sample(1);
    assert_eq!(single.pixel_offset, Vec2::splat(0.5));
    assert_eq!(one.dimension(), 4);
    let mut many = sampler.pixel(10, 0);
    let first = many.camera_sample(16);
    assert_eq!(many.dimension(), 4);
    assert_ne!(first.pixel_offset, Vec2::splat(0.5));
    // The lens sample does not depend on the sample count.
    assert_eq!(first.lens, single.lens);
}

#[test]
fn a_sample_does_not_depend_on_the_sample_count() {
    // Sample i of a 16-sample render is sample i of a 64-sample render: a render of more
    // samples, or of a range of samples, extends a smaller one.
    let sampler = Sampler::new(3);
    for index in 0..16 {
        let a = sampler.pixel(99, index).camera_sample(16);
        let b = sampler.pixel(99, index).camera_sample(64);
        assert_eq!(a, b, "{index}");
    }
}

#[test]
fn draws_equal_the_sobol_definitions() {
    // The draws scramble mirrored bits (`sobol::dimension_1_mirrored`,
    // `scramble::scramble_mirrored`); they must equal the scramble of the Sobol points
    // computed from their definitions, bit for bit.
    use super::scramble::{hash_u32, hash_words, nested_uniform_scramble, unit_float};
    use super::sobol;
    for seed in [0u32, 7, 1_000_003] {
        let sampler = Sampler::new(seed);
        for pixel in [0u32, 1, 517, 262_143, 4_000_000] {
            for index in [0u32, 1, 2, 3, 15, 16, 255, 1023, 65_537] {
                let mut draws = sampler.pixel(pixel, index);
                let pixel_key = hash_words(&[seed, pixel]);
                for dimension in (0..12u32).step_by(3) {
                    let key = hash_words(&[pixel_key, dimension]);
                    let shuffled = nested_uniform_scramble(index, key);
                    let x = nested_uniform_scramble(
                        sobol::dimension_0(shuffled),
                        hash_u32(key ^ 0x5bd1_e995),
                    );
                    let y = nested_uniform_scramble(
                        sobol::dimension_1(shuffled),
                        hash_u32(key ^ 0x1b87_3593),
                    );
                    let pair = draws.next_2d();
                    assert_eq!(pair.x.to_bits(), unit_float(x).to_bits());
                    assert_eq!(pair.y.to_bits(), unit_float(y).to_bits());
                    let key = hash_words(&[pixel_key, dimension + 2]);
                    let shuffled = nested_uniform_scramble(index, key);
                    let single = nested_uniform_scramble(
                        sobol::dimension_0(shuffled),
                        hash_u32(key ^ 0x5bd1_e995),
                    );
                    assert_eq!(draws.next_1d().to_bits(), unit_float(single).to_bits());
                }
            }
        }
    }
}

#[test]
fn a_camera_sample_without_the_lens_keeps_the_dimensions() {
    let sampler = Sampler::new(11);
    for spp in [1u32, 4] {
        for index in 0..spp {
            let mut full = sampler.pixel(321, index);
            let mut pinhole = sampler.pixel(321, index);
            let a = full.camera_sample(spp);
            let b = pinhole.camera_sample_drawing(spp, false);
            assert_eq!(a.pixel_offset, b.pixel_offset);
            assert_eq!(b.lens, Vec2::splat(0.5));
            assert_eq!(pinhole.dimension(), 4);
            assert_eq!(full.next_2d(), pinhole.next_2d());
        }
    }
}

#[test]
fn camera_lanes_are_the_one_pixel_draws_bit_for_bit() {
    // The packet form of the camera's draws gives every lane the values, and the sampler
    // state, that one pixel at a time gives: with and without a lens, at one sample per
    // pixel (the centre) and more, compiled for every vector level this processor has.
    let mut state = 0x9e37_79b9u32;
    let mut next = move || crate::test_rng::xorshift32(&mut state);
    for seed in [0u32, 7, u32::MAX] {
        let sampler = Sampler::new(seed);
        for spp in [1u32, 4, 16, 1000] {
            for lens in [false, true] {
                for _ in 0..20 {
                    // Different pixels, then one pixel's different samples.
                    let pixels: [u32; 16] = std::array::from_fn(|_| next() % 4_000_000);
                    let index = next() % spp;
                    let same_index = [index; 16];
                    let one_pixel = [pixels[0]; 16];
                    let indices: [u32; 16] = std::array::from_fn(|_| next() % spp);
                    // Runs of lanes of one pixel, a pixel coming back after another.
                    let runs: [u32; 16] =
                        std::array::from_fn(|lane| pixels[[0, 1, 0, 2][lane / 4]]);
                    for (pixels, indices) in [
                        (&pixels, &same_index),
                        (&one_pixel, &indices),
                        (&runs, &indices),
                    ] {
                        for level in simd::Level::supported() {
                            let lanes = simd::run_at(
                                level,
                                #[inline(always)]
                                || sampler.camera_lanes_inline(pixels, indices, spp, lens),
                            );
                            for (lane, (&pixel, &index)) in pixels.iter().zip(indices).enumerate() {
                                let mut one = sampler.pixel(pixel, index);
                                let sample = one.camera_sample_drawing(spp, lens);
                                let offset =
                                    Vec2::new(lanes.offset[0][lane], lanes.offset[1][lane]);
                                let on_lens = Vec2::new(lanes.lens[0][lane], lanes.lens[1][lane]);
                                assert_eq!(
                                    offset.to_array().map(f32::to_bits),
                                    sample.pixel_offset.to_array().map(f32::to_bits)
                                );
                                assert_eq!(
                                    on_lens.to_array().map(f32::to_bits),
                                    sample.lens.to_array().map(f32::to_bits)
                                );
                                let mut packed = lanes.samplers[lane];
                                assert_eq!(
                                    packed, one,
                                    "seed {seed}, pixel {pixel}, index {index}"
                                );
                                assert_eq!(packed.next_2d(), one.next_2d());
                            }
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn sampler_lanes_draw_what_each_sampler_draws_bit_for_bit() {
    // Paths at different pixels, samples and depths: every lane's 1D and 2D draws at its own
    // dimension plus an offset are the draws of its sampler, compiled for every vector
    // level this processor has, and the samplers are not moved on.
    let mut state = 0x2545_f491u32;
    let mut next = move || crate::test_rng::xorshift32(&mut state);
    for seed in [0u32, 11, u32::MAX] {
        let sampler = Sampler::new(seed);
        for _ in 0..40 {
            let samplers: [PixelSampler; 16] = std::array::from_fn(|_| {
                let mut one = sampler.pixel(next() % 4_000_000, next() % 4096);
                one.skip_dimensions(next() % 200);
                one
            });
            let offset = next() % 8;
            for level in simd::Level::supported() {
                let (one_d, two_d) = simd::run_at(
                    level,
                    #[inline(always)]
                    || {
                        let lanes = SamplerLanes::new(&samplers);
                        (lanes.draw_1d(offset), lanes.draw_2d(offset))
                    },
                );
                for (lane, one) in samplers.iter().enumerate() {
                    let mut ahead = *one;
                    ahead.skip_dimensions(offset);
                    let mut ahead_2d = ahead;
                    assert_eq!(
                        one_d[lane].to_bits(),
                        ahead.next_1d().to_bits(),
                        "{level:?}"
                    );
                    let point = ahead_2d.next_2d();
                    assert_eq!(two_d[0][lane].to_bits(), point.x.to_bits(), "{level:?}");
                    assert_eq!(two_d[1][lane].to_bits(), point.y.to_bits(), "{level:?}");
                }
            }
        }
    }
}
