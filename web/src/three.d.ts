import { BufferGeometry, Loader, LoadingManager, Material } from 'three';
import { Decoder, DecoderOptions, PmzStatus } from './index.js';

export interface PMZOptions extends DecoderOptions {
  /** Keep a pmzMorph attribute (parent position, birth time) for geomorphMaterial(). */
  geomorph?: boolean;
  /** Refinement time per update() in milliseconds (default 8). */
  frameBudgetMs?: number;
  /** false: the caller calls stream.update() itself (default: every animation frame). */
  autoUpdate?: boolean;
}

/** One stream's geometry, updated in place (changed ranges only) by update(). */
export declare class PMZStream {
  constructor(decoder: Decoder, options?: PMZOptions);
  readonly decoder: Decoder;
  readonly geometry: BufferGeometry;
  /** null: follow the stream to the finest level; a number: hold that face count. */
  faceTarget: number | null;
  bytes: number;
  totalBytes: number;
  status: PmzStatus;
  /** Every byte fed, finish() ok and (when following the stream) the finest level shown. */
  complete: boolean;
  readonly error: string;
  readonly faceCount: number;
  readonly vertexCount: number;
  /** Resolves to the final status once every byte is fed (set by PMZLoader.stream()). */
  done?: Promise<PmzStatus>;
  feed(bytes: Uint8Array): PmzStatus;
  finish(): PmzStatus;
  /** Refines within budgetMs and copies what changed into the geometry; true if it changed. */
  update(budgetMs?: number): boolean;
  dispose(): void;
}

/** Lets new vertices glide from their parent's position; call the result every frame. */
export declare function geomorphMaterial(material: Material, seconds?: number): () => void;

export declare class PMZLoader extends Loader<BufferGeometry> {
  constructor(manager?: LoadingManager, options?: PMZOptions);
  options: PMZOptions;
  load(
    url: string,
    onLoad?: (geometry: BufferGeometry, stream: PMZStream) => void,
    onProgress?: (event: { loaded: number; total: number; stream: PMZStream }) => void,
    onError?: (error: unknown) => void,
  ): void;
  stream(
    source: string | URL | Response | ReadableStream<Uint8Array> | Blob,
    onUpdate?: (stream: PMZStream) => void,
  ): Promise<PMZStream & { done: Promise<PmzStatus> }>;
}
