//! Kernels kept per (frequency, options), and the medium of many (frequency, rain rate) pairs
//! at once (each distinct frequency's kernel built once, in parallel).

use super::*;

type KernelCache = Mutex<HashMap<String, Arc<RainKernel>>>;

/// Kernels already built, keyed by frequency and options. Bounded: cleared when full.
fn kernel_cache() -> &'static KernelCache {
    static CACHE: OnceLock<KernelCache> = OnceLock::new();
    CACHE.get_or_init(|| Mutex::new(HashMap::new()))
}

const KERNEL_CACHE_CAPACITY: usize = 1024;

/// Empties the kernel cache (benchmarks use it to time cold starts).
pub fn clear_kernel_cache() {
    if let Ok(mut cache) = kernel_cache().lock() {
        cache.clear();
    }
}

/// The kernel for `(freq_hz, opts)`, from the cache or built and cached.
pub fn cached_kernel(freq_hz: f64, opts: &MediumOptions) -> Result<Arc<RainKernel>> {
    // Debug formatting of f64 round-trips exactly, so equal keys mean equal inputs.
    let key = format!("{:?}|{:?}", freq_hz.to_bits(), opts);
    if let Some(k) = kernel_cache()
        .lock()
        .ok()
        .and_then(|c| c.get(&key).cloned())
    {
        return Ok(k);
    }
    let kernel = Arc::new(RainKernel::new(freq_hz, opts)?);
    if let Ok(mut cache) = kernel_cache().lock() {
        if cache.len() >= KERNEL_CACHE_CAPACITY {
            cache.clear();
        }
        cache.insert(key, kernel.clone());
    }
    Ok(kernel)
}

/// The medium for many `(freq_hz[i], rain_rate_mm_h[i])` pairs (equal lengths). Every input
/// is checked before any work; kernels are built once per distinct frequency, in parallel.
pub fn effective_many(
    freq_hz: ArrayView1<'_, f64>,
    rain_rate_mm_h: ArrayView1<'_, f64>,
    opts: &MediumOptions,
) -> Result<Vec<Effective>> {
    if freq_hz.len() != rain_rate_mm_h.len() {
        return Err(CoreError::invalid(
            "rain_rate_mm_h",
            "must have as many values as freq_hz",
            rain_rate_mm_h.len(),
        ));
    }
    opts.validate()?;
    freq_hz.iter().try_for_each(|&f| check_freq(f))?;
    rain_rate_mm_h
        .iter()
        .try_for_each(|&r| check_rain_rate(r))?;

    let mut distinct: Vec<u64> = freq_hz.iter().map(|f| f.to_bits()).collect();
    distinct.sort_unstable();
    distinct.dedup();
    let kernels: Vec<Arc<RainKernel>> = distinct
        .par_iter()
        .map(|&bits| cached_kernel(f64::from_bits(bits), opts))
        .collect::<Result<_>>()?;
    let index: HashMap<u64, usize> = distinct.iter().enumerate().map(|(i, &b)| (b, i)).collect();
    let pairs: Vec<(usize, f64)> = freq_hz
        .iter()
        .zip(rain_rate_mm_h.iter())
        .map(|(f, &r)| (index[&f.to_bits()], r))
        .collect();
    Ok(pairs
        .par_iter()
        .with_min_len(256)
        .map(|&(k, r)| kernels[k].evaluate_unchecked(r))
        .collect())
}

/// Specific attenuation (dB/km) for many pairs; see [`effective_many`].
pub fn specific_attenuation_many(
    freq_hz: ArrayView1<'_, f64>,
    rain_rate_mm_h: ArrayView1<'_, f64>,
    opts: &MediumOptions,
) -> Result<Array1<f64>> {
    Ok(effective_many(freq_hz, rain_rate_mm_h, opts)?
        .into_iter()
        .map(|e| e.gamma_db_per_km)
        .collect())
}
