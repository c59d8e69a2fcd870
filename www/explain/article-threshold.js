// The verdict's threshold in words: the core's MIN_EXPLAINED (src/parts/diagnosis.rs, wasm minExplained), as the
// app's verdict prints it ("97.5 %"); "the core's threshold" when the pool has not said it.
export const thresholdText = (x) => (Number.isFinite(x) ? `${(100 * x).toFixed(1)} %` : 'the core’s threshold');
